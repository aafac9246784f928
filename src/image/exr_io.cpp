#include "image/exr_io.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/memory.h"

#include <OpenEXR/Iex.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfTestFile.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <exception>
#include <filesystem>
#include <memory>
#include <new>
#include <cstdint>
#include <utility>

namespace vdbmarch {

namespace {

int channelCount(Imf::InputFile& in) {
    int n = 0;
    for (auto it = in.header().channels().begin(); it != in.header().channels().end(); ++it) ++n;
    return n;
}

const char* const RgbaNames[4] = {"R", "G", "B", "A"};

// A damaged header can claim any data window (fuzzing: 11 GB asked of a
// 1 kB file). Deflate shrinks at most ~1032:1 and every chunk costs bytes of
// its own, so a window whose samples (at least 2 bytes each, as halfs) need
// over 2^20 times the file's size cannot be in the file, whatever its
// compression (a wide margin: a constant 16k x 16k RGBA image still passes).
void checkDataWindowFits(const std::string& path, int64_t w, int64_t h, int channels, uint64_t fileBytes) {
    if (w <= 0 || h <= 0 || w > (1 << 30) / h)
        throw InputError(str(path, ": unsupported data window of ", w, "x", h));
    const uint64_t minSampleBytes = uint64_t(w) * uint64_t(h) * 2 * uint64_t(std::max(1, channels));
    if ((minSampleBytes >> 20) > fileBytes)
        throw InputError(str(path, ": the header claims a ", w, "x", h, " data window that a file of ", fileBytes,
                             " bytes cannot hold (damaged header?)"));
}

// Bytes of the value of an OpenEXR attribute type read at a fixed size
// (OpenEXR 3.1's TypedAttribute<T>::readValueFrom reads the type, whatever
// the size field says); 0 for the types read by their size or content.
int fixedExrValueBytes(const std::string& type) {
    static const std::pair<const char*, int> kTypes[] = {
        {"box2i", 16}, {"box2f", 16}, {"compression", 1}, {"lineOrder", 1}, {"envmap", 1}, {"deepImageState", 1},
        {"int", 4}, {"float", 4}, {"double", 8}, {"v2i", 8}, {"v2f", 8}, {"v2d", 16}, {"v3i", 12}, {"v3f", 12},
        {"v3d", 24}, {"m33f", 36}, {"m33d", 72}, {"m44f", 64}, {"m44d", 128}, {"chromaticities", 32},
        {"keycode", 28}, {"rational", 8}, {"timecode", 8}, {"tiledesc", 9}};
    for (const auto& [t, n] : kTypes)
        if (type == t) return n;
    return 0;
}

// OpenEXR allocates (and clears) what an attribute's size field claims
// before reading its value: fuzzing found a 1.3 kB file whose string
// attribute asks for gigabytes. Walk the header(s) first, as the format
// lays them out (magic, version, then per header: name\0 type\0 int32 size,
// value; a NUL name ends a header; multi-part files end with an empty
// header), and refuse any size that the rest of the file cannot hold.
void checkExrAttributeSizes(const std::string& path, std::FILE* f) {
    std::error_code ec;
    const uint64_t fileBytes = uint64_t(std::filesystem::file_size(path, ec));
    unsigned char head[8];
    if (ec || std::fread(head, 1, 8, f) != 8) return;  // OpenEXR reports short files itself
    const bool multiPart = (head[5] & 0x10) != 0;  // version flag bit 12
    auto readString = [&](std::string& s) {
        s.clear();
        for (int c; (c = std::fgetc(f)) != 0;) {
            if (c == EOF || s.size() >= 255)
                throw InputError(str(path, ": damaged OpenEXR header (an attribute name or type runs on)"));
            s.push_back(char(c));
        }
    };
    std::string name, type;
    int channels = 1;  // until the channel list is read (OpenEXR writes it first)
    while (true) {
        while (true) {
            readString(name);
            if (name.empty()) break;
            readString(type);
            unsigned char b[4];
            if (std::fread(b, 1, 4, f) != 4)
                throw InputError(str(path, ": damaged OpenEXR header (cut inside attribute '", name, "')"));
            const int32_t size = int32_t(uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24);
            const long pos = std::ftell(f);
            const uint64_t left = pos >= 0 && uint64_t(pos) <= fileBytes ? fileBytes - uint64_t(pos) : 0;
            if (size < 0 || uint64_t(size) > left)
                throw InputError(str(path, ": damaged OpenEXR header: attribute '", name, "' (", type, ") claims ",
                                     size, " bytes, but only ", left, " follow"));
            // OpenEXR reads the value of a type it knows by the type, not by
            // the size field (fuzzing: a channel list whose size disagreed
            // sent our walk and OpenEXR's apart), so follow it: fixed-size
            // types take their own size, a channel list its entries (name\0
            // and 16 bytes each, up to an empty name).
            const int fixed = fixedExrValueBytes(type);
            if (fixed > 0 && type != "box2i") {
                std::fseek(f, fixed, SEEK_CUR);
                continue;
            }
            if (type == "chlist") {
                channels = 0;
                for (std::string channel;;) {
                    readString(channel);
                    if (channel.empty()) break;
                    ++channels;
                    if (std::fseek(f, 16, SEEK_CUR) != 0)
                        throw InputError(str(path, ": damaged OpenEXR header (cut inside the channel list)"));
                }
                continue;
            }
            // A preview image is allocated from its own width and height.
            if (type == "preview") {
                unsigned char wh[8];
                if (std::fread(wh, 1, 8, f) != 8) break;
                const uint64_t pw = uint64_t(wh[0]) | uint64_t(wh[1]) << 8 | uint64_t(wh[2]) << 16 | uint64_t(wh[3]) << 24;
                const uint64_t ph = uint64_t(wh[4]) | uint64_t(wh[5]) << 8 | uint64_t(wh[6]) << 16 | uint64_t(wh[7]) << 24;
                if (pw * ph * 4 > left)
                    throw InputError(str(path, ": damaged OpenEXR header: the preview image claims ", pw, "x", ph,
                                         " pixels, but only ", left, " bytes follow"));
                std::fseek(f, long(pw * ph * 4), SEEK_CUR);
                continue;
            }
            // A string vector: each string's own length is allocated first.
            if (type == "stringvector") {
                int64_t read = 0;
                while (read < size) {
                    unsigned char l[4];
                    if (std::fread(l, 1, 4, f) != 4) break;
                    const int32_t len = int32_t(uint32_t(l[0]) | uint32_t(l[1]) << 8 | uint32_t(l[2]) << 16 | uint32_t(l[3]) << 24);
                    read += 4;
                    if (len < 0 || int64_t(len) > int64_t(size) - read)
                        throw InputError(str(path, ": damaged OpenEXR header: a string of attribute '", name,
                                             "' claims ", len, " bytes, beyond the attribute's ", size));
                    std::fseek(f, len, SEEK_CUR);
                    read += len;
                }
                continue;
            }
            // The data window too, before OpenEXR sizes its line buffers by it
            // (fuzzing: 160 MB of buffers for a 434-byte file).
            if (type == "box2i") {
                unsigned char box[16];
                if (std::fread(box, 1, 16, f) != 16) break;
                int32_t v[4];
                for (int k = 0; k < 4; ++k)
                    v[k] = int32_t(uint32_t(box[4 * k]) | uint32_t(box[4 * k + 1]) << 8 | uint32_t(box[4 * k + 2]) << 16 |
                                   uint32_t(box[4 * k + 3]) << 24);
                if (name == "dataWindow")
                    checkDataWindowFits(path, int64_t(v[2]) - v[0] + 1, int64_t(v[3]) - v[1] + 1, channels, fileBytes);
                continue;
            }
            std::fseek(f, size, SEEK_CUR);
        }
        if (!multiPart) break;
        // Multi-part: headers follow one another until an empty one.
        const int c = std::fgetc(f);
        if (c == 0 || c == EOF) break;
        std::ungetc(c, f);
    }
}

// Missing / unreadable files are IoError; everything OpenEXR rejects after
// that is a bad input file.
void checkReadableExr(const std::string& path) {
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) throw IoError(str(path, ": cannot open: ", std::strerror(errno)));
    std::fclose(f);
    if (!Imf::isOpenExrFile(path.c_str()))
        throw InputError(str(path, ": not an OpenEXR file"));
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), std::fclose);
    if (file) checkExrAttributeSizes(path, file.get());
}

// Runs `fn` with an open InputFile, translating OpenEXR's exceptions into ours.
template <typename Fn>
auto withInputFile(const std::string& path, Fn fn) -> decltype(fn(std::declval<Imf::InputFile&>())) {
    checkReadableExr(path);
    try {
        Imf::InputFile in(path.c_str());
        return fn(in);
    } catch (const InputError&) {
        throw;
    } catch (const Iex::ErrnoExc& e) {
        throw IoError(str(path, ": cannot read: ", printableExcerpt(e.what())));
    } catch (const std::bad_alloc&) {
        throw InputError(str(path, ": cannot read OpenEXR: out of memory (corrupt header?)"));
    } catch (const std::exception& e) {
        throw InputError(str(path, ": cannot read OpenEXR: ", printableExcerpt(e.what())));
    }
}

}  // namespace

void writeExr(const std::string& path, const Image& img, const StringAttributes& attributes,
              const std::vector<ExrLayer>& layers, const std::optional<ExrWindow>& window) {
    if (img.empty()) throw std::logic_error(str(path, ": cannot write: image is empty"));
    if (img.rgba.size() != img.pixelCount() * 4)
        throw std::logic_error(str(path, ": cannot write: pixel buffer does not match ", img.width,
                             "x", img.height));
    const ExrWindow win = window ? *window : wholeFrame(img);
    if (win.data.width() != img.width || win.data.height() != img.height || win.display.x0 != 0 ||
        win.display.y0 != 0 || !win.display.contains(win.data))
        throw std::logic_error(str(path, ": cannot write: data window [", win.data.x0, ", ", win.data.x1, ") x [",
                             win.data.y0, ", ", win.data.y1, ") of a ", img.width, "x", img.height,
                             " image does not fit the ", win.display.width(), "x", win.display.height(), " frame"));
    const Imath::Box2i displayWindow(Imath::V2i(0, 0), Imath::V2i(win.display.x1 - 1, win.display.y1 - 1));
    const Imath::Box2i dataWindow(Imath::V2i(win.data.x0, win.data.y0), Imath::V2i(win.data.x1 - 1, win.data.y1 - 1));

    Imf::Header header(displayWindow, dataWindow);
    header.compression() = Imf::ZIP_COMPRESSION;
    for (const char* name : RgbaNames) header.channels().insert(name, Imf::Channel(Imf::FLOAT));
    for (const auto& [name, value] : attributes) {
        // Replacing a standard attribute (e.g. "compression") or a duplicate
        // would silently change the file; refuse instead.
        if (name.empty() || header.find(name) != header.end())
            throw std::logic_error(str(path, ": cannot write: duplicate or reserved EXR attribute name '",
                                 name, "'"));
        header.insert(name, Imf::StringAttribute(value));
    }

    // Slices address pixels by their frame coordinates (Slice::Make offsets
    // the base by the data window). OpenEXR's Slice wants a non-const base,
    // but only reads through it when writing.
    const size_t xStride = 4 * sizeof(float), yStride = xStride * size_t(img.width);
    float* base = const_cast<float*>(img.rgba.data());
    Imf::FrameBuffer fb;
    for (int c = 0; c < 4; ++c)
        fb.insert(RgbaNames[c], Imf::Slice::Make(Imf::FLOAT, base + c, dataWindow, xStride, yStride));

    for (const ExrLayer& layer : layers) {
        const size_t n = layer.channels.size();
        if (layer.name.empty() || n == 0 || layer.pixels.size() != img.pixelCount() * n)
            throw std::logic_error(str(path, ": cannot write: layer '", layer.name, "' does not hold ", n,
                                 " channel(s) of ", img.width, "x", img.height, " pixels"));
        for (size_t c = 0; c < n; ++c) {
            const std::string name = layer.name + "." + layer.channels[c];
            if (header.channels().findChannel(name))
                throw std::logic_error(str(path, ": cannot write: duplicate channel '", name, "'"));
            header.channels().insert(name, Imf::Channel(Imf::FLOAT));
            float* layerBase = const_cast<float*>(layer.pixels.data()) + c;
            fb.insert(name, Imf::Slice::Make(Imf::FLOAT, layerBase, dataWindow, n * sizeof(float),
                                             n * sizeof(float) * size_t(img.width)));
        }
    }

    AtomicFile file(path);
    try {
        // Scoped so the file is closed (fully flushed) before the rename.
        Imf::OutputFile out(file.tempPath().c_str(), header);
        out.setFrameBuffer(fb);
        out.writePixels(img.height);
    } catch (const std::exception& e) {
        throw IoError(str(path, ": cannot write: ", e.what()));
    }
    file.commit();
}

namespace {

// String attributes of a header, in name order (OpenEXR iterates so).
StringAttributes stringAttributes(const Imf::Header& header) {
    StringAttributes out;
    for (auto it = header.begin(); it != header.end(); ++it)
        if (auto* s = dynamic_cast<const Imf::StringAttribute*>(&it.attribute())) out.emplace_back(it.name(), s->value());
    return out;
}

// The data window's R, G, B (A if present, else 1) and, with `allChannels`,
// every other channel grouped into layers by the name before its last '.',
// all as FLOAT; both windows; the string attributes.
ExrContents readContents(const std::string& path, Imf::InputFile& in, bool allChannels) {
    const Imath::Box2i dw = in.header().dataWindow(), dispw = in.header().displayWindow();
    const int64_t w = int64_t(dw.max.x) - dw.min.x + 1, h = int64_t(dw.max.y) - dw.min.y + 1;
    const int channels = channelCount(in);
    std::error_code ec;
    const uint64_t fileBytes = uint64_t(std::filesystem::file_size(path, ec));
    checkDataWindowFits(path, w, h, channels, ec ? UINT64_MAX : fileBytes);
    const int floatsPerPixel = allChannels ? std::max(4, channels + 1) : 4;
    checkMemory(uint64_t(w) * uint64_t(h) * uint64_t(floatsPerPixel) * sizeof(float),
                str(path, " (", w, "x", h, " pixels, ", floatsPerPixel, " floats each)"));
    const Imf::ChannelList& list = in.header().channels();
    for (int c = 0; c < 3; ++c)
        if (!list.findChannel(RgbaNames[c])) throw InputError(str(path, ": no ", RgbaNames[c], " channel"));

    ExrContents out;
    out.window.data = {dw.min.x, dw.min.y, dw.max.x + 1, dw.max.y + 1};
    out.window.display = {dispw.min.x, dispw.min.y, dispw.max.x + 1, dispw.max.y + 1};
    out.image = Image(int(w), int(h));
    Imf::FrameBuffer fb;
    // A missing A channel is filled with 1 (opaque) by OpenEXR.
    for (int c = 0; c < 4; ++c)
        fb.insert(RgbaNames[c], Imf::Slice::Make(Imf::FLOAT, out.image.rgba.data() + c, dw, 4 * sizeof(float),
                                                 4 * sizeof(float) * size_t(w), 1, 1, c == 3 ? 1.0 : 0.0));
    for (auto it = list.begin(); allChannels && it != list.end(); ++it) {
        const std::string name = it.name();
        if (name == "R" || name == "G" || name == "B" || name == "A") continue;
        const size_t dot = name.rfind('.');
        const std::string layer = dot == std::string::npos ? std::string() : name.substr(0, dot);
        const std::string channel = dot == std::string::npos ? name : name.substr(dot + 1);
        if (out.layers.empty() || out.layers.back().name != layer) out.layers.push_back({layer, {}, {}});
        out.layers.back().channels.push_back(channel);
    }
    for (ExrLayer& l : out.layers) {
        const size_t n = l.channels.size();
        l.pixels.assign(size_t(w) * size_t(h) * n, 0.f);
        for (size_t c = 0; c < n; ++c)
            fb.insert(l.name.empty() ? l.channels[c] : l.name + "." + l.channels[c],
                      Imf::Slice::Make(Imf::FLOAT, l.pixels.data() + c, dw, n * sizeof(float),
                                       n * sizeof(float) * size_t(w)));
    }
    in.setFrameBuffer(fb);
    in.readPixels(dw.min.y, dw.max.y);
    out.attributes = stringAttributes(in.header());
    return out;
}

}  // namespace

Image readExr(const std::string& path) {
    return withInputFile(path, [&](Imf::InputFile& in) { return readContents(path, in, false).image; });
}

ExrContents readExrContents(const std::string& path) {
    return withInputFile(path, [&](Imf::InputFile& in) { return readContents(path, in, true); });
}

const ExrLayer* findLayer(const std::vector<ExrLayer>& layers, const std::string& name) {
    for (const ExrLayer& l : layers)
        if (l.name == name) return &l;
    return nullptr;
}

std::vector<float> layerChannel(const ExrLayer& layer, const std::string& c, size_t pixels) {
    const auto it = std::find(layer.channels.begin(), layer.channels.end(), c);
    if (it == layer.channels.end()) return {};
    const size_t k = size_t(it - layer.channels.begin()), n = layer.channels.size();
    std::vector<float> out(pixels);
    for (size_t p = 0; p < pixels; ++p) out[p] = layer.pixels[p * n + k];
    return out;
}

StringAttributes readExrStringAttributes(const std::string& path) {
    return withInputFile(path, [](Imf::InputFile& in) { return stringAttributes(in.header()); });
}

}  // namespace vdbmarch
