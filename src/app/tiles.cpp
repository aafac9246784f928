#include "app/tiles.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <map>
#include <set>

#include <nlohmann/json.hpp>

#include "app/command_line.h"
#include "app/denoise_frame.h"
#include "core/hash.h"
#include "core/memory.h"
#include "render/render.h"

namespace vdbmarch {

TileRequest parseTileRequest(const std::string& tile, const std::string& crop, const std::string& passes) {
    TileRequest r;
    if (int(!tile.empty()) + int(!crop.empty()) + int(!passes.empty()) > 1)
        throw InputError(str(tile.empty() ? "" : str("--tile ", tile, " "), crop.empty() ? "" : str("--crop ", crop, " "),
                             passes.empty() ? "" : str("--passes ", passes, " "),
                             "given together: a render is split one way, by tiles, by a crop or by passes"));
    char extra = 0;
    if (!passes.empty()) {
        if (std::sscanf(passes.c_str(), "%d-%d%c", &r.firstPass, &r.endPass, &extra) != 2 || r.firstPass < 0 ||
            r.endPass <= r.firstPass)
            throw InputError(str("--passes ", passes, ": expected FIRST-END, photon passes FIRST to END-1 (0-based), "
                                 "e.g. 0-4"));
    }
    if (!tile.empty()) {
        if (std::sscanf(tile.c_str(), "%d/%d%c", &r.index, &r.count, &extra) != 2)
            throw InputError(str("--tile ", tile, ": expected INDEX/COUNT with a 0-based index, e.g. 0/4"));
        if (r.count < 1) throw InputError(str("--tile ", tile, ": the tile count must be at least 1"));
        if (r.index < 0 || r.index >= r.count)
            throw InputError(str("--tile ", tile, ": the tile index must be 0 to ", r.count - 1, " (0-based)"));
    }
    if (!crop.empty()) {
        PixelRect& c = r.crop;
        if (std::sscanf(crop.c_str(), "%d,%d,%d,%d%c", &c.x0, &c.y0, &c.x1, &c.y1, &extra) != 4)
            throw InputError(str("--crop ", crop, ": expected x0,y0,x1,y1 in pixels (x1, y1 excluded), e.g. 0,0,320,240"));
        if (c.empty())
            throw InputError(str("--crop ", crop, ": empty; x0 < x1 and y0 < y1 are needed (x1, y1 excluded)"));
        r.cropped = true;
    }
    return r;
}

PixelRect windowOf(const TileRequest& r, int width, int height) {
    if (r.count > 0) return tileOfFrame(r.index, r.count, width, height);
    if (!r.cropped) return {0, 0, width, height};
    if (!PixelRect{0, 0, width, height}.contains(r.crop))
        throw InputError(str("--crop ", r.crop.x0, ",", r.crop.y0, ",", r.crop.x1, ",", r.crop.y1,
                             ": not inside the ", width, "x", height, " frame (0 <= x0 < x1 <= ", width,
                             ", 0 <= y0 < y1 <= ", height, ")"));
    return r.crop;
}

StringAttributes tileAttributes(const TileRequest& r, const RenderResult& result) {
    if (r.byPasses()) {
        std::string samples;
        for (const PhotonPassSums& p : result.passSums) samples += str(samples.empty() ? "" : ",", p.pass, ":", p.samples);
        return {{TileSplitAttribute, str(result.totalPhotonPasses, " passes")},
                {TileAttribute, str(r.firstPass, "-", r.endPass)},
                {PassSamplesAttribute, samples}};
    }
    if (r.count > 0) return {{TileSplitAttribute, str(r.count, " bands")}, {TileAttribute, str(r.index, "/", r.count)}};
    if (r.cropped)
        return {{TileSplitAttribute, "crop"},
                {TileAttribute, str(r.crop.x0, ",", r.crop.y0, ",", r.crop.x1, ",", r.crop.y1)}};
    return {};
}

const char* denoiseModeName(RenderSettings::Denoise mode) {
    return mode == RenderSettings::Denoise::On ? "on" : mode == RenderSettings::Denoise::Off ? "off" : "preview";
}

StringAttributes noiseAttributes(const NoiseEstimate& e) {
    if (!e.valid) return {};
    return {{NoiseAttribute, str(e.relative())}, {NoiseRmseAttribute, str(e.rmse)}, {NoiseMeanAttribute, str(e.mean)}};
}

std::vector<ExrLayer> passLayers(const RenderResult& result) {
    std::vector<ExrLayer> layers;
    // Each pass's sums, and those of its odd-index samples (the noise estimate).
    for (const PhotonPassSums& p : result.passSums)
        for (const bool odd : {false, true}) {
            ExrLayer l{str("pass", p.pass, odd ? "odd" : ""), {"R", "G", "B", "T"}, {}};
            l.pixels.reserve(p.L.size() * 4);
            for (size_t i = 0; i < p.L.size(); ++i) {
                const Color c = (odd ? p.oddL[i] : p.L[i]).rounded();
                l.pixels.insert(l.pixels.end(), {c.x, c.y, c.z, float(odd ? p.oddT[i] : p.T[i])});
            }
            layers.push_back(std::move(l));
            // The emitted part's sums (RenderOptions::keepEmitted).
            if (p.E.empty()) continue;
            ExrLayer e{str("pass", p.pass, odd ? "emittedodd" : "emitted"), {"R", "G", "B"}, {}};
            e.pixels.reserve(p.E.size() * 3);
            for (size_t i = 0; i < p.E.size(); ++i) {
                const Color c = (odd ? p.oddE[i] : p.E[i]).rounded();
                e.pixels.insert(e.pixels.end(), {c.x, c.y, c.z});
            }
            layers.push_back(std::move(e));
        }
    return layers;
}

std::string renderHash(const SceneDesc& desc, const std::string& cacheFile) {
    nlohmann::json j = nlohmann::json::parse(desc.jsonText);
    if (j.contains("render") && j["render"].is_object()) j["render"].erase("threads");
    Fnv1a h;
    const std::string text = j.dump() + "\n" + VDBMARCH_VERSION + "\n" + cacheFile;
    h.add(text.data(), text.size());
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h.value));
    return buf;
}

namespace {

struct Tile {
    std::string path;
    ExrContents contents;
    std::map<std::string, std::string> attributes;
    int index = -1, count = 0;  // of a band split
    int firstPass = -1, endPass = -1;          // of a split by passes
    std::vector<std::pair<int, int>> samples;  // (pass, samples) of a split by passes
    const std::string& attribute(const std::string& name) const {
        static const std::string none = "(none)";
        auto it = attributes.find(name);
        return it == attributes.end() ? none : it->second;
    }
};

std::string describe(const PixelRect& r) {
    return str("[", r.x0, ", ", r.x1, ") x [", r.y0, ", ", r.y1, ")");
}

// Attributes that differ between the tiles of one render: the tile itself,
// its time, and the effective scene text (which records render.threads;
// vdbmarch:renderHash stands for the rest of it).
bool perTileAttribute(const std::string& name, bool timed, bool byPasses) {
    static const std::set<std::string> always = {TileAttribute, "vdbmarch:renderSeconds", "vdbmarch:scene",
                                                 NoiseAttribute, NoiseRmseAttribute, NoiseMeanAttribute,
                                                 "vdbmarch:meanSpp"};
    // A tile given a time budget renders as many samples as fit; a part by
    // passes renders the samples of its passes.
    static const std::set<std::string> samples = {"vdbmarch:spp", "vdbmarch:photonPasses", PassSamplesAttribute};
    return always.count(name) || ((timed || byPasses) && samples.count(name));
}

// The attributes of the merged frame: the first tile's, without the tile's
// own, with the tiles' total time and `replaced` values.
StringAttributes mergedAttributes(const std::vector<Tile>& tiles, const std::map<std::string, std::string>& replaced) {
    const Tile& ref = tiles.front();
    double seconds = 0;
    for (const Tile& t : tiles) seconds += std::atof(t.attribute("vdbmarch:renderSeconds").c_str());
    StringAttributes out;
    for (const auto& [k, v] : ref.contents.attributes) {
        if (k == TileSplitAttribute || k == TileAttribute || k == PassSamplesAttribute) continue;
        auto it = replaced.find(k);
        out.emplace_back(k, k == "vdbmarch:renderSeconds" ? str(seconds) : it != replaced.end() ? it->second : v);
    }
    for (const auto& [k, v] : replaced)
        if (!ref.attributes.count(k)) out.emplace_back(k, v);
    out.emplace_back("vdbmarch:mergedFrom", str(tiles.size(), " tiles (", ref.attribute(TileSplitAttribute), ")"));
    return out;
}

// "merge: 2 of 8 <what> missing: a, b; nothing written" for the indices in
// [0, count) that `present` lacks (the first 8 named by `name`); "" if none.
template <class Name>
std::string missingMessage(const std::vector<bool>& present, const char* what, Name name) {
    std::string list;
    int n = 0;
    for (size_t i = 0; i < present.size(); ++i)
        if (!present[i]) {
            if (n < 8) list += str(n ? ", " : "", name(int(i)));
            ++n;
        }
    return n ? str("merge: ", n, " of ", present.size(), " ", what, " missing: ", list, n > 8 ? ", ..." : "",
                   "; nothing written")
             : std::string();
}

// Parts by passes: every pass of the render once, folded in pass order into
// the totals exactly as one process does (PixelSums), then averaged.
MergedTiles mergePasses(const std::vector<Tile>& parts) {
    const Tile& ref = parts.front();
    const int total = std::atoi(ref.attribute(TileSplitAttribute).c_str());
    const PixelRect frame = ref.contents.window.display;
    std::vector<const Tile*> owner(size_t(total), nullptr);
    for (const Tile& t : parts) {
        if (t.contents.window.data != frame)
            throw InputError(str(t.path, ": damaged part: a part by passes covers the whole frame ", describe(frame),
                                 ", not ", describe(t.contents.window.data)));
        if (t.endPass > total)
            throw InputError(str(t.path, ": damaged part: passes ", t.firstPass, "-", t.endPass, " of ", total));
        for (int p = t.firstPass; p < t.endPass; ++p) {
            if (owner[size_t(p)])
                throw InputError(str(owner[size_t(p)]->path, " and ", t.path, " both hold photon pass ", p));
            owner[size_t(p)] = &t;
        }
    }
    std::vector<bool> present(static_cast<size_t>(total), false);
    for (int p = 0; p < total; ++p) present[size_t(p)] = owner[size_t(p)] != nullptr;
    const std::string missing = missingMessage(present, "photon passes", [](int p) { return str(p); });
    if (!missing.empty()) throw InputError(missing);
    const size_t pixels = size_t(frame.width()) * size_t(frame.height());
    PixelSums sums(pixels);
    for (int p = 0; p < total; ++p) {
        const Tile& t = *owner[size_t(p)];
        int samples = 0;
        for (const auto& [q, k] : t.samples)
            if (q == p) samples = k;
        PhotonPassSums pass;
        pass.pass = p;
        pass.samples = samples;
        for (const bool odd : {false, true}) {
            const std::string name = str("pass", p, odd ? "odd" : "");
            const ExrLayer* layer = findLayer(t.contents.layers, name);
            if (!layer || layer->channels != std::vector<std::string>{"B", "G", "R", "T"} || samples <= 0)
                throw InputError(str(t.path, ": damaged part: no layer ", name, " (B, G, R, T) or no sample count for it"));
            std::vector<ColorSum>& L = odd ? pass.oddL : pass.L;
            std::vector<double>& T = odd ? pass.oddT : pass.T;
            L.resize(pixels);
            T.resize(pixels);
            // The file's channels are in name order: B, G, R, T.
            for (size_t i = 0; i < pixels; ++i) {
                const float* v = &layer->pixels[4 * i];
                L[i] = ColorSum(Color(v[2], v[1], v[0]));
                T[i] = v[3];
            }
            // The emitted part's sums, where the parts kept them (B, G, R).
            const std::string emittedName = str("pass", p, odd ? "emittedodd" : "emitted");
            for (const ExrLayer& l : t.contents.layers) {
                if (l.name != emittedName) continue;
                if (l.channels != std::vector<std::string>{"B", "G", "R"})
                    throw InputError(str(t.path, ": damaged part: layer ", emittedName, " is not B, G, R"));
                std::vector<ColorSum>& E = odd ? pass.oddE : pass.E;
                E.resize(pixels);
                for (size_t i = 0; i < pixels; ++i) {
                    const float* v = &l.pixels[3 * i];
                    E[i] = ColorSum(Color(v[2], v[1], v[0]));
                }
            }
        }
        if (pass.E.size() != pass.oddE.size())
            throw InputError(str(t.path, ": damaged part: pass ", p, " has one of its two emitted layers only"));
        sums.fold(pass);
    }
    MergedTiles out;
    out.frame.image = sums.average(frame.width(), frame.height());
    out.frame.window = {frame, frame};
    std::map<std::string, std::string> replaced = {{"vdbmarch:spp", str(sums.samples)},
                                                   {"vdbmarch:photonPasses", str(total)}};
    for (auto& [k, v] : noiseAttributes(estimateNoise(sums))) replaced[k] = v;
    out.frame.attributes = mergedAttributes(parts, replaced);
    // The two half renders for the denoiser, as one process would keep them.
    if (ref.attributes.count(DenoiseAttribute) && ref.attribute(DenoiseAttribute) != "off" && sums.samples >= 2) {
        for (const bool odd : {false, true}) {
            const Image half = odd ? sums.oddHalf(frame.width(), frame.height()) : sums.evenHalf(frame.width(), frame.height());
            out.frame.layers.push_back({odd ? "odd" : "even", {"R", "G", "B", "A"}, half.rgba});
        }
        if (!sums.E.empty())
            for (const bool odd : {false, true}) {
                const Image half = sums.emittedHalf(frame.width(), frame.height(), odd);
                out.frame.layers.push_back(rgbLayer(odd ? EmittedOddLayer : EmittedEvenLayer, half));
            }
    }
    return out;
}

// "4-16", or "16" when all agree.
std::string valueRange(const std::vector<Tile>& tiles, const std::string& name) {
    int lo = 0, hi = 0;
    bool first = true;
    for (const Tile& t : tiles) {
        const int v = std::atoi(t.attribute(name).c_str());
        lo = first ? v : std::min(lo, v);
        hi = first ? v : std::max(hi, v);
        first = false;
    }
    return lo == hi ? str(lo) : str(lo, "-", hi);
}

// A tile's file and its header: which band, crop or passes it holds.
Tile readTile(const std::string& path) {
    Tile t;
    t.path = path;
    t.contents = readExrContents(path);
    for (const auto& [k, v] : t.contents.attributes) t.attributes[k] = v;
    if (!t.attributes.count(TileSplitAttribute) || !t.attributes.count(TileAttribute))
        throw InputError(str(path, ": not a vdbmarch tile (no ", TileSplitAttribute,
                             " attribute): render tiles with --tile I/N or --crop"));
    const std::string& split = t.attribute(TileSplitAttribute);
    const size_t space = split.find(' ');
    if (space != std::string::npos && split.substr(space) == " passes") {
        char extra = 0;
        const int total = std::atoi(split.c_str());
        if (std::sscanf(t.attribute(TileAttribute).c_str(), "%d-%d%c", &t.firstPass, &t.endPass, &extra) != 2 ||
            split != str(total, " passes") || total < 1 || t.firstPass < 0 || t.endPass <= t.firstPass)
            throw InputError(str(path, ": damaged part header: ", TileSplitAttribute, " = \"", split, "\", ",
                                 TileAttribute, " = \"", t.attribute(TileAttribute), "\""));
        for (const std::string& item : splitList(t.attribute(PassSamplesAttribute))) {
            int p = 0, k = 0;
            if (std::sscanf(item.c_str(), "%d:%d%c", &p, &k, &extra) != 2)
                throw InputError(str(path, ": damaged part header: ", PassSamplesAttribute, " = \"",
                                     t.attribute(PassSamplesAttribute), "\""));
            t.samples.emplace_back(p, k);
        }
    } else if (split != "crop") {
        char extra = 0;
        if (std::sscanf(t.attribute(TileAttribute).c_str(), "%d/%d%c", &t.index, &t.count, &extra) != 2 ||
            split != str(t.count, " bands") || t.index < 0 || t.index >= t.count)
            throw InputError(str(path, ": damaged tile header: ", TileSplitAttribute, " = \"", split, "\", ",
                                 TileAttribute, " = \"", t.attribute(TileAttribute), "\""));
    }
    return t;
}

// Every tile against the first: the same split, frame, scene and settings
// (any vdbmarch:* attribute but the per-tile ones), and the same AOV layers.
void checkSameRender(const std::vector<Tile>& tiles, bool timed) {
    const Tile& ref = tiles.front();
    // The split and frame first, the named settings next, the hash of the
    // rest of the scene last, so the message names the most telling one.
    std::vector<std::string> keys = {TileSplitAttribute, "vdbmarch:frame"};
    std::set<std::string> named;
    for (const Tile& t : tiles)
        for (const auto& kv : t.attributes)
            if (kv.first.rfind("vdbmarch:", 0) == 0 && kv.first != RenderHashAttribute &&
                std::find(keys.begin(), keys.end(), kv.first) == keys.end())
                named.insert(kv.first);
    keys.insert(keys.end(), named.begin(), named.end());
    keys.push_back(RenderHashAttribute);
    for (const Tile& t : tiles) {
        if (&t == &ref) continue;
        for (const std::string& k : keys) {
            if (perTileAttribute(k, timed, ref.firstPass >= 0) || t.attribute(k) == ref.attribute(k)) continue;
            throw InputError(str(t.path, ": belongs to another render than ", ref.path, ": ", k, " is \"",
                                 printableExcerpt(t.attribute(k)), "\" there and \"", printableExcerpt(ref.attribute(k)),
                                 "\" in ", ref.path,
                                 k == RenderHashAttribute ? " (another scene, settings, version or cache)" : ""));
        }
        if (t.contents.window.display != ref.contents.window.display)
            throw InputError(str(t.path, ": belongs to another render than ", ref.path, ": its frame is ",
                                 t.contents.window.display.width(), "x", t.contents.window.display.height(), ", not ",
                                 ref.contents.window.display.width(), "x", ref.contents.window.display.height()));
        if (ref.firstPass >= 0) continue;  // parts by passes hold one layer per pass
        bool sameLayers = t.contents.layers.size() == ref.contents.layers.size();
        for (size_t i = 0; sameLayers && i < t.contents.layers.size(); ++i)
            sameLayers = t.contents.layers[i].name == ref.contents.layers[i].name &&
                         t.contents.layers[i].channels == ref.contents.layers[i].channels;
        if (!sameLayers)
            throw InputError(str(t.path, ": belongs to another render than ", ref.path, ": its AOV layers differ"));
    }
}

// The bands or crops lie inside the frame where their headers say, and
// cover it exactly once: duplicates, overlaps and holes are named.
void checkCoverage(const std::vector<Tile>& tiles, const PixelRect& frame) {
    const Tile& ref = tiles.front();
    for (const Tile& t : tiles) {
        const PixelRect& d = t.contents.window.data;
        if (frame.x0 != 0 || frame.y0 != 0 || !frame.contains(d))
            throw InputError(str(t.path, ": damaged tile: its data window ", describe(d), " is not inside the frame ",
                                 describe(frame)));
        if (t.count > 0 && d != tileOfFrame(t.index, t.count, frame.width(), frame.height()))
            throw InputError(str(t.path, ": damaged tile: tile ", t.index, "/", t.count, " should cover ",
                                 describe(tileOfFrame(t.index, t.count, frame.width(), frame.height())), ", not ",
                                 describe(d)));
    }
    // Duplicates and overlaps, then holes.
    for (size_t i = 0; i < tiles.size(); ++i)
        for (size_t j = i + 1; j < tiles.size(); ++j) {
            const Tile &a = tiles[i], &b = tiles[j];
            if (a.count > 0 && a.index == b.index)
                throw InputError(str("tile ", a.index, "/", a.count, " is given twice: ", a.path, " and ", b.path));
            if (a.contents.window.data.overlaps(b.contents.window.data))
                throw InputError(str(a.path, " and ", b.path, " overlap: ", describe(a.contents.window.data), " and ",
                                     describe(b.contents.window.data)));
        }
    uint64_t covered = 0;
    for (const Tile& t : tiles) covered += uint64_t(t.contents.image.pixelCount());
    const uint64_t framePixels = uint64_t(frame.width()) * uint64_t(frame.height());
    if (covered != framePixels) {
        if (ref.count > 0) {
            std::vector<bool> present(size_t(ref.count), false);
            for (const Tile& t : tiles) present[size_t(t.index)] = true;
            throw InputError(missingMessage(present, "tiles", [&](int i) {
                const PixelRect r = tileOfFrame(i, ref.count, frame.width(), frame.height());
                return str(i, "/", ref.count, " (rows ", r.y0, "-", r.y1 - 1, ")");
            }));
        }
        checkMemory(framePixels, "the coverage map of the frame");
        std::vector<char> hit(framePixels, 0);
        for (const Tile& t : tiles) {
            const PixelRect& d = t.contents.window.data;
            for (int y = d.y0; y < d.y1; ++y)
                std::fill_n(hit.begin() + int64_t(y) * frame.width() + d.x0, d.width(), 1);
        }
        const size_t hole = size_t(std::find(hit.begin(), hit.end(), 0) - hit.begin());
        throw InputError(str("merge: the crops cover ", covered, " of the ", framePixels, " pixels of the ",
                             frame.width(), "x", frame.height(), " frame; the first hole is at pixel (",
                             hole % size_t(frame.width()), ", ", hole / size_t(frame.width()), "); nothing written"));
    }
}

// The frame from its bands or crops: RGBA and every layer, row by row; the
// header's noise and sample counts combined over the tiles.
MergedTiles assembleFrame(const std::vector<Tile>& tiles, const PixelRect& frame, bool timed) {
    const Tile& ref = tiles.front();
    const uint64_t framePixels = uint64_t(frame.width()) * uint64_t(frame.height());
    size_t floatsPerPixel = 4;
    for (const ExrLayer& l : ref.contents.layers) floatsPerPixel += l.channels.size();
    checkMemory(framePixels * floatsPerPixel * sizeof(float), str("the merged ", frame.width(), "x", frame.height(), " frame"));
    MergedTiles out;
    ExrContents& m = out.frame;
    m.image = Image(frame.width(), frame.height());
    m.window = {frame, frame};
    for (const ExrLayer& l : ref.contents.layers)
        m.layers.push_back({l.name, l.channels, std::vector<float>(framePixels * l.channels.size())});
    for (const Tile& t : tiles) {
        const PixelRect& d = t.contents.window.data;
        auto copyRows = [&](const std::vector<float>& from, std::vector<float>& to, size_t n) {
            for (int y = d.y0; y < d.y1; ++y)
                std::copy_n(from.begin() + int64_t(y - d.y0) * d.width() * int64_t(n), size_t(d.width()) * n,
                            to.begin() + (int64_t(y) * frame.width() + d.x0) * int64_t(n));
        };
        copyRows(t.contents.image.rgba, m.image.rgba, 4);
        for (size_t i = 0; i < m.layers.size(); ++i)
            copyRows(t.contents.layers[i].pixels, m.layers[i].pixels, m.layers[i].channels.size());
    }
    std::map<std::string, std::string> replaced;
    if (timed)
        for (const char* k : {"vdbmarch:spp", "vdbmarch:photonPasses"}) replaced[k] = valueRange(tiles, k);
    // The frame's noise from the tiles': mean squared error and mean weighted by their pixels.
    NoiseEstimate noise;
    noise.valid = true;
    double spp = 0;
    for (const Tile& t : tiles) {
        const double share = double(t.contents.image.pixelCount()) / double(framePixels);
        noise.valid = noise.valid && t.attributes.count(NoiseRmseAttribute) && t.attributes.count(NoiseMeanAttribute);
        const double rmse = std::atof(t.attribute(NoiseRmseAttribute).c_str());
        noise.rmse += share * rmse * rmse;
        noise.mean += share * std::atof(t.attribute(NoiseMeanAttribute).c_str());
        spp += share * std::atof(t.attribute("vdbmarch:meanSpp").c_str());
    }
    noise.rmse = std::sqrt(noise.rmse);
    for (auto& [k, v] : noiseAttributes(noise)) replaced[k] = v;
    if (ref.attributes.count("vdbmarch:meanSpp")) replaced["vdbmarch:meanSpp"] = str(spp);
    m.attributes = mergedAttributes(tiles, replaced);
    if (timed && valueRange(tiles, "vdbmarch:spp").find('-') != std::string::npos)
        out.warnings.push_back(str("the tiles were rendered with a time budget or a noise target and reached ", valueRange(tiles, "vdbmarch:spp"),
                                   " samples per pixel: noise (and, with photons, bias) may differ between tiles"));
    return out;
}

}  // namespace

MergedTiles mergeTiles(const std::vector<std::string>& paths) {
    if (paths.empty()) throw InputError("merge: no tiles given");
    std::vector<Tile> tiles;
    tiles.reserve(paths.size());
    for (const std::string& path : paths) tiles.push_back(readTile(path));
    const Tile& ref = tiles.front();
    // A time budget or a noise target: tiles render as many samples as they need.
    const bool timed = ref.attribute("vdbmarch:timeBudget") != "none" ||
                       (ref.attributes.count(NoiseTargetAttribute) && ref.attribute(NoiseTargetAttribute) != "none");
    checkSameRender(tiles, timed);
    if (ref.firstPass >= 0) return mergePasses(tiles);
    const PixelRect frame = ref.contents.window.display;
    checkCoverage(tiles, frame);
    return assembleFrame(tiles, frame, timed);
}

}  // namespace vdbmarch
