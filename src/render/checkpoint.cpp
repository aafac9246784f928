#include "render/checkpoint.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <utility>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"

namespace vdbmarch {

namespace {

constexpr int CheckpointFormat = 3;
const char* const Magic = "vdbmarch checkpoint ";

// FNV-1a over 64-bit words (the last partial word zero-padded): a checksum
// against damage and truncation, eight times faster than byte-wise FNV on
// the hundreds of megabytes of a large frame's sums.
class WordHash {
public:
    void add(const char* p, size_t n) {
        while (n > 0) {
            const size_t take = std::min(n, sizeof(uint64_t) - mFill);
            std::memcpy(reinterpret_cast<char*>(&mWord) + mFill, p, take);
            mFill += take;
            p += take;
            n -= take;
            if (mFill == sizeof(uint64_t)) flushWord();
            // Whole words straight from the input.
            while (mFill == 0 && n >= sizeof(uint64_t)) {
                std::memcpy(&mWord, p, sizeof mWord);
                flushWord();
                p += sizeof(uint64_t);
                n -= sizeof(uint64_t);
            }
        }
    }
    uint64_t value() {
        if (mFill > 0) {
            std::memset(reinterpret_cast<char*>(&mWord) + mFill, 0, sizeof(uint64_t) - mFill);
            flushWord();
        }
        return mValue;
    }

private:
    void flushWord() {
        mValue = (mValue ^ mWord) * 1099511628211ULL;
        mWord = 0;
        mFill = 0;
    }
    uint64_t mValue = 1469598103934665603ULL, mWord = 0;
    size_t mFill = 0;
};

// Writes the file's bytes and hashes them as they go (no copy of the sums).
class HashedWriter {
public:
    explicit HashedWriter(std::ofstream& out) : mOut(out) {}
    void bytes(const char* p, size_t n) {
        mOut.write(p, std::streamsize(n));
        mHash.add(p, n);
    }
    template <typename T>
    void array(const std::vector<T>& v) {
        bytes(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
    }
    void pass(const PhotonPassSums& p) {
        array(p.L);
        array(p.T);
        array(p.oddL);
        array(p.oddT);
        array(p.E);
        array(p.oddE);
    }
    void finish() {
        const uint64_t h = mHash.value();
        mOut.write(reinterpret_cast<const char*>(&h), sizeof h);
    }

private:
    std::ofstream& mOut;
    WordHash mHash;
};

nlohmann::json passHeader(const PhotonPassSums& p) {
    return {{"pass", p.pass}, {"samples", p.samples}, {"pixels", p.L.size()}, {"emitted", p.E.size()}};
}

// Reads the arrays back in the order they were written, never past the end.
class Reader {
public:
    Reader(const std::string& path, const char* data, size_t size) : mPath(path), mData(data), mSize(size) {}
    template <typename T>
    void array(std::vector<T>& v, size_t n) {
        const size_t bytes = n * sizeof(T);
        if (n > mSize / sizeof(T) || mAt + bytes > mSize)
            throw InputError(str(mPath, ": the checkpoint's arrays are shorter than its header says (damaged)"));
        v.resize(n);
        if (bytes) std::memcpy(v.data(), mData + mAt, bytes);
        mAt += bytes;
    }
    void pass(PhotonPassSums& p, const nlohmann::json& h) {
        p.pass = h.at("pass").get<int>();
        p.samples = h.at("samples").get<int>();
        const size_t n = h.at("pixels").get<size_t>();
        array(p.L, n);
        array(p.T, n);
        array(p.oddL, n);
        array(p.oddT, n);
        const size_t e = h.at("emitted").get<size_t>();
        array(p.E, e);
        array(p.oddE, e);
    }
    bool done() const { return mAt == mSize; }

private:
    std::string mPath;
    const char* mData;
    size_t mSize, mAt = 0;
};

}  // namespace

void writeCheckpointFile(const std::string& path, const CheckpointIdentity& id, const RenderCheckpoint& c) {
    const RenderCounters& k = c.counters;
    nlohmann::json h = {
        {"version", id.version},
        {"render_hash", id.renderHash},
        {"window", id.window},
        {"budget", id.budget},
        {"next_sample", c.nextSample},
        {"seconds", c.seconds},
        {"counters",
         {k.cameraRays, k.surfaceHits, k.marchSamples, k.liSamples, k.shadowRays, k.shadowSamples, k.nonFiniteSamples,
          k.marchedLength, k.skippedLength}},
        {"pixels", c.sums.L.size()},
        {"sums_samples", c.sums.samples},
        {"converged", c.sums.convergedAt.size()},
        {"emitted", c.sums.E.size()},
        {"open", passHeader(c.open)},
        {"aovs",
         {{"depth", c.aovs.depth.size()},
          {"albedo", c.aovs.albedo.size()},
          {"normal", c.aovs.normal.size()},
          {"direct", c.aovs.direct.size()}}},
    };
    nlohmann::json passes = nlohmann::json::array();
    for (const PhotonPassSums& p : c.passSums) passes.push_back(passHeader(p));
    h["passes"] = passes;
    const std::string head = str(Magic, CheckpointFormat, "\n", h.dump(), "\n");
    AtomicFile file(path);
    {
        std::ofstream out(file.tempPath(), std::ios::binary);
        HashedWriter w(out);
        w.bytes(head.data(), head.size());
        w.array(c.sums.L);
        w.array(c.sums.T);
        w.array(c.sums.oddL);
        w.array(c.sums.oddT);
        w.array(c.sums.convergedAt);
        w.array(c.sums.E);
        w.array(c.sums.oddE);
        w.pass(c.open);
        for (const PhotonPassSums& p : c.passSums) w.pass(p);
        w.array(c.aovs.depth);
        w.array(c.aovs.depthSamples);
        w.array(c.aovs.albedo);
        w.array(c.aovs.normal);
        w.array(c.aovs.direct);
        w.finish();
        out.flush();
        if (!out) throw IoError(str(path, ": cannot write: ", std::strerror(errno)));
    }
    file.commit();
}

void saveCheckpoint(const CheckpointHooks& hooks, RenderCheckpoint& c, Film& film) {
    c.sums = std::move(film.sums);
    c.open = std::move(film.open);
    c.passSums = std::move(film.passSums);
    c.aovs = std::move(film.aovs);
    struct GiveBack {
        RenderCheckpoint& c;
        Film& film;
        ~GiveBack() {
            film.sums = std::move(c.sums);
            film.open = std::move(c.open);
            film.passSums = std::move(c.passSums);
            film.aovs = std::move(c.aovs);
        }
    } giveBack{c, film};
    hooks.save(c);
}

void resumeFilm(const RenderCheckpoint& c, Film& film) {
    film.sums = c.sums;
    film.open = c.open;
    film.passSums = c.passSums;
    film.aovs = c.aovs;
}

RenderCheckpoint readCheckpointFile(const std::string& path, const CheckpointIdentity& expected) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(str(path, ": cannot read the checkpoint (", std::strerror(errno), ")"));
    std::ostringstream buffer;
    buffer << in.rdbuf();
    const std::string bytes = buffer.str();
    const std::string magic = str(Magic, CheckpointFormat, "\n");
    if (bytes.compare(0, std::strlen(Magic), Magic) != 0)
        throw InputError(str(path, ": not a vdbmarch checkpoint"));
    if (bytes.compare(0, magic.size(), magic) != 0)
        throw InputError(str(path, ": a checkpoint of another format (this build reads format ", CheckpointFormat, ")"));
    uint64_t stored = 0;
    if (bytes.size() < magic.size() + sizeof stored)
        throw InputError(str(path, ": the checkpoint is truncated (", bytes.size(), " bytes)"));
    const size_t body = bytes.size() - sizeof stored;
    std::memcpy(&stored, bytes.data() + body, sizeof stored);
    WordHash hash;
    hash.add(bytes.data(), body);
    if (hash.value() != stored)
        throw InputError(str(path, ": the checkpoint is damaged or truncated (its checksum does not match); "
                               "delete it to render from the start"));
    const size_t eol = bytes.find('\n', magic.size());
    if (eol == std::string::npos || eol >= body) throw InputError(str(path, ": the checkpoint has no header"));
    RenderCheckpoint c;
    try {
        const nlohmann::json h = nlohmann::json::parse(bytes.begin() + long(magic.size()), bytes.begin() + long(eol));
        auto expect = [&](const char* key, const std::string& want, const char* what) {
            const std::string got = h.at(key).get<std::string>();
            if (got != want)
                throw InputError(str(path, ": the checkpoint was written for ", what, " (", got, "; this render: ", want,
                                     "); delete it, or render what it was written for"));
        };
        expect("version", expected.version, "another vdbmarch version");
        expect("render_hash", expected.renderHash, "another scene or other settings (render hash)");
        expect("window", expected.window, "other pixels (tile or crop)");
        expect("budget", expected.budget, "another sample budget");
        c.nextSample = h.at("next_sample").get<int>();
        c.seconds = h.at("seconds").get<double>();
        const auto& k = h.at("counters");
        RenderCounters& r = c.counters;
        uint64_t* ints[] = {&r.cameraRays, &r.surfaceHits, &r.marchSamples, &r.liSamples,
                            &r.shadowRays, &r.shadowSamples, &r.nonFiniteSamples};
        for (size_t i = 0; i < 7; ++i) *ints[i] = k.at(i).get<uint64_t>();
        r.marchedLength = k.at(7).get<double>();
        r.skippedLength = k.at(8).get<double>();
        Reader read(path, bytes.data() + eol + 1, body - eol - 1);
        const size_t pixels = h.at("pixels").get<size_t>();
        read.array(c.sums.L, pixels);
        read.array(c.sums.T, pixels);
        read.array(c.sums.oddL, pixels);
        read.array(c.sums.oddT, pixels);
        read.array(c.sums.convergedAt, h.at("converged").get<size_t>());
        read.array(c.sums.E, h.at("emitted").get<size_t>());
        read.array(c.sums.oddE, h.at("emitted").get<size_t>());
        c.sums.samples = h.at("sums_samples").get<int>();
        read.pass(c.open, h.at("open"));
        for (const auto& p : h.at("passes")) {
            c.passSums.emplace_back();
            read.pass(c.passSums.back(), p);
        }
        const auto& a = h.at("aovs");
        read.array(c.aovs.depth, a.at("depth").get<size_t>());
        read.array(c.aovs.depthSamples, a.at("depth").get<size_t>());
        read.array(c.aovs.albedo, a.at("albedo").get<size_t>());
        read.array(c.aovs.normal, a.at("normal").get<size_t>());
        read.array(c.aovs.direct, a.at("direct").get<size_t>());
        if (!read.done()) throw InputError(str(path, ": the checkpoint has bytes its header does not describe (damaged)"));
    } catch (const nlohmann::json::exception& e) {
        throw InputError(str(path, ": the checkpoint's header is not what this build writes (", e.what(), ")"));
    }
    return c;
}

}  // namespace vdbmarch
