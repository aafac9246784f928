#include "parse/json_locate.h"

#include <algorithm>
#include <cctype>

namespace vdbmarch {

namespace {

// A lenient walk over text that nlohmann's parser has already accepted.
class Locator {
public:
    Locator(const std::string& text, const std::string& target) : mText(text), mTarget(target) {}

    size_t run() {
        skipSpace();
        value("");
        return mFound;
    }

private:
    void skipSpace() {
        while (mPos < mText.size() && std::isspace(static_cast<unsigned char>(mText[mPos]))) ++mPos;
    }
    bool done() const { return mFound != std::string::npos || mPos >= mText.size(); }

    std::string stringToken() {
        std::string out;
        ++mPos;  // opening quote
        while (mPos < mText.size() && mText[mPos] != '"') {
            if (mText[mPos] == '\\' && mPos + 1 < mText.size()) {
                out += mText[mPos + 1];
                mPos += 2;
            } else {
                out += mText[mPos++];
            }
        }
        ++mPos;  // closing quote
        return out;
    }

    void value(const std::string& path) {
        if (done()) return;
        char c = mText[mPos];
        if (c == '{') {
            ++mPos;
            for (skipSpace(); !done() && mText[mPos] != '}'; skipSpace()) {
                if (mText[mPos] == ',') { ++mPos; continue; }
                size_t keyStart = mPos;
                std::string key = stringToken();
                std::string keyPath = path.empty() ? key : path + "." + key;
                if (keyPath == mTarget) { mFound = keyStart; return; }
                skipSpace();
                if (mPos < mText.size() && mText[mPos] == ':') ++mPos;
                skipSpace();
                value(keyPath);
            }
            ++mPos;
        } else if (c == '[') {
            ++mPos;
            size_t index = 0;
            for (skipSpace(); !done() && mText[mPos] != ']'; skipSpace()) {
                if (mText[mPos] == ',') { ++mPos; continue; }
                std::string itemPath = path + "[" + std::to_string(index++) + "]";
                if (itemPath == mTarget) { mFound = mPos; return; }
                value(itemPath);
            }
            ++mPos;
        } else if (c == '"') {
            stringToken();
        } else {
            while (mPos < mText.size() && mText[mPos] != ',' && mText[mPos] != ']' && mText[mPos] != '}' &&
                   !std::isspace(static_cast<unsigned char>(mText[mPos])))
                ++mPos;
        }
    }

    const std::string& mText;
    const std::string& mTarget;
    size_t mPos = 0;
    size_t mFound = std::string::npos;
};

}  // namespace

size_t locateJsonPath(const std::string& text, const std::string& path) {
    if (path.empty()) return std::string::npos;
    return Locator(text, path).run();
}

void lineAndColumn(const std::string& text, size_t offset, size_t& line, size_t& column) {
    line = 1;
    size_t lineStart = 0;
    for (size_t i = 0; i < offset && i < text.size(); ++i)
        if (text[i] == '\n') {
            ++line;
            lineStart = i + 1;
        }
    column = offset - lineStart + 1;
}

std::string caretExcerpt(const std::string& text, size_t offset) {
    size_t line, col;
    lineAndColumn(text, offset, line, col);
    const size_t lineStart = std::min(offset, text.size()) + 1 - col;
    const size_t lineEnd = text.find('\n', lineStart);
    std::string excerpt = text.substr(lineStart, lineEnd == std::string::npos ? std::string::npos : lineEnd - lineStart);
    if (excerpt.size() > 120) excerpt = excerpt.substr(0, 120) + "...";
    return "\n    " + excerpt + "\n    " + std::string(col > 0 ? col - 1 : 0, ' ') + "^";
}

}  // namespace vdbmarch
