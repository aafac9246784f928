#include "parse/frames.h"

#include <cctype>

#include "core/error.h"

namespace vdbmarch {

bool hasFrameToken(const std::string& path) { return path.find('#') != std::string::npos; }

std::string substituteFrame(const std::string& pattern, int frame) {
    if (frame < 0) throw InputError(str("frame ", frame, ": frames must be non-negative"));
    const std::string digits = std::to_string(frame);
    std::string out;
    out.reserve(pattern.size() + digits.size());
    for (size_t i = 0; i < pattern.size();) {
        if (pattern[i] != '#') {
            out += pattern[i++];
            continue;
        }
        size_t run = 0;
        while (i < pattern.size() && pattern[i] == '#') ++i, ++run;
        if (digits.size() < run) out.append(run - digits.size(), '0');
        out += digits;
    }
    return out;
}

namespace {

// A whole non-negative number at text[pos...], advancing pos; false when
// there is no digit there or it exceeds kMaxFrame.
bool readNumber(const std::string& text, size_t& pos, long long& value) {
    const size_t start = pos;
    value = 0;
    while (pos < text.size() && std::isdigit(static_cast<unsigned char>(text[pos]))) {
        value = value * 10 + (text[pos] - '0');
        if (value > kMaxFrame) return false;
        ++pos;
    }
    return pos > start;
}

}  // namespace

std::vector<int> parseFrameRange(const std::string& text, const std::string& option) {
    const std::string usage = str(option, " ", text.empty() ? "\"\"" : text, ": ");
    const std::string expected = "expected N, A-B or A-B:STEP in whole non-negative frame numbers (e.g. 1-100, 1-100:2)";
    long long first = 0, last = 0, step = 1;
    size_t pos = 0;
    if (!readNumber(text, pos, first)) {
        if (pos < text.size() && text[pos] == '-') throw InputError(usage + "frames must be non-negative; " + expected);
        throw InputError(usage + (pos < text.size() && std::isdigit(static_cast<unsigned char>(text[pos]))
                                      ? str("frame numbers are at most ", kMaxFrame)
                                      : expected));
    }
    last = first;
    if (pos < text.size() && text[pos] == '-') {
        ++pos;
        if (!readNumber(text, pos, last))
            throw InputError(usage + (pos < text.size() && std::isdigit(static_cast<unsigned char>(text[pos]))
                                          ? str("frame numbers are at most ", kMaxFrame)
                                          : expected));
        if (pos < text.size() && text[pos] == ':') {
            ++pos;
            if (!readNumber(text, pos, step) || pos != text.size())
                throw InputError(usage + "the step must be a whole number of at least 1; " + expected);
            if (step < 1) throw InputError(usage + "the step must be at least 1");
        }
    }
    if (pos != text.size()) throw InputError(usage + expected);
    if (last < first) throw InputError(usage + str("the last frame ", last, " is before the first ", first));
    const long long count = (last - first) / step + 1;
    if (count > kMaxFrameCount)
        throw InputError(usage + str(count, " frames; one run renders at most ", kMaxFrameCount,
                                     " (split the range over several runs)"));
    std::vector<int> frames;
    for (long long f = first; f <= last; f += step) frames.push_back(int(f));
    return frames;
}

}  // namespace vdbmarch
