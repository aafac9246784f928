#include "parse/mesh.h"

#include "core/error.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <cctype>
#include <cfloat>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <unordered_map>

namespace vdbmarch {

namespace {

// ---------------------------------------------------------------- helpers

std::string toLower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return s;
}

std::string extensionOf(const std::string& path) {
    size_t slash = path.find_last_of('/');
    size_t dot = path.find_last_of('.');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
    return toLower(path.substr(dot));
}

std::string directoryOf(const std::string& path) {
    size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? std::string("./") : path.substr(0, slash + 1);
}

// Whole file in memory: meshes are small next to the volumes, and one buffer
// makes bounds checks on binary PLY trivial.
std::string readWholeFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(str(path, ": cannot open mesh file"));
    // A directory opens fine on Linux but fails to read; libstdc++ reports
    // that by throwing from the stream buffer.
    try {
        std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        if (!in.bad()) return data;
    } catch (const std::exception& e) {
        throw IoError(str(path, ": cannot read mesh file: ", e.what()));
    }
    throw IoError(str(path, ": cannot read mesh file"));
}

// Appends one polygon fan-triangulated (v0, vi, vi+1), after checking every
// index against the vertex count. indexBase turns stored 0-based indices back
// into the numbering the file uses so messages match what the user sees.
void appendPolygon(TriangleMesh& mesh, const int64_t* idx, size_t n, size_t faceNumber, int64_t indexBase,
                   const std::string& path, size_t& droppedTriangles) {
    const int64_t vertexCount = int64_t(mesh.positions.size());
    for (size_t k = 0; k < n; ++k) {
        if (idx[k] < 0 || idx[k] >= vertexCount) {
            throw InputError(str(path, ": face ", faceNumber, " references vertex index ", idx[k] + indexBase,
                                 ", out of range for ", vertexCount, " vertices"));
        }
    }
    if (n < 3) {
        // Points and lines bound nothing.
        ++droppedTriangles;
        return;
    }
    for (size_t k = 1; k + 1 < n; ++k) {
        uint32_t a = uint32_t(idx[0]), b = uint32_t(idx[k]), c = uint32_t(idx[k + 1]);
        if (a == b || b == c || a == c) {
            ++droppedTriangles;
            continue;
        }
        mesh.indices.insert(mesh.indices.end(), {a, b, c});
    }
}

void checkPositions(const TriangleMesh& mesh, const std::string& path) {
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        const Vec3& p = mesh.positions[i];
        if (!isFinite(p)) {
            throw InputError(str(path, ": vertex ", i, " has a non-finite coordinate (", p.x, ", ", p.y, ", ", p.z,
                                 ")"));
        }
    }
}

void finishMesh(const TriangleMesh& mesh, const std::string& path, size_t droppedTriangles) {
    if (mesh.triangleCount() == 0) throw InputError(str(path, ": mesh has no (non-degenerate) triangles"));
    if (droppedTriangles > 0) {
        warn(str(path, ": dropped ", droppedTriangles, " degenerate triangle(s) or face(s) with fewer than 3 vertices"));
    }
}

// ---------------------------------------------------------------- OBJ

TriangleMesh loadObj(const std::string& path) {
    std::string data = readWholeFile(path);
    std::istringstream in(data);
    tinyobj::attrib_t attrib;
    std::vector<tinyobj::shape_t> shapes;
    std::vector<tinyobj::material_t> materials;
    std::string objWarn, objErr;
    tinyobj::MaterialFileReader materialReader(directoryOf(path));
    // Our own triangulation: tinyobjloader silently skips faces with bad
    // indices when it triangulates, and we want to report those.
    bool ok = tinyobj::LoadObj(&attrib, &shapes, &materials, &objWarn, &objErr, &in, &materialReader,
                               /*triangulate=*/false);
    auto trimmed = [](std::string s) {
        while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
        return s;
    };
    if (!ok) throw InputError(str(path, ": invalid OBJ: ", trimmed(objErr)));

    TriangleMesh mesh;
    mesh.positions.reserve(attrib.vertices.size() / 3);
    for (size_t i = 0; i + 2 < attrib.vertices.size(); i += 3) {
        mesh.positions.emplace_back(attrib.vertices[i], attrib.vertices[i + 1], attrib.vertices[i + 2]);
    }
    checkPositions(mesh, path);

    size_t faceNumber = 0, dropped = 0;
    std::vector<int64_t> polygon;
    for (const tinyobj::shape_t& shape : shapes) {
        const tinyobj::mesh_t& m = shape.mesh;
        size_t offset = 0;
        for (unsigned char n : m.num_face_vertices) {
            if (offset + n > m.indices.size()) break;  // caught by the check below
            polygon.clear();
            for (size_t k = 0; k < n; ++k) polygon.push_back(m.indices[offset + k].vertex_index);
            // OBJ numbers vertices from 1.
            appendPolygon(mesh, polygon.data(), n, faceNumber++, 1, path, dropped);
            offset += n;
        }
        // tinyobjloader stores face sizes in a byte, so larger faces desync.
        if (offset != m.indices.size()) {
            throw InputError(str(path, ": a face in shape '", shape.name,
                                 "' has more than 255 vertices, which the OBJ reader cannot represent"));
        }
    }
    if (!trimmed(objWarn).empty()) warn(str(path, ": ", trimmed(objWarn)));
    finishMesh(mesh, path, dropped);
    return mesh;
}

// ---------------------------------------------------------------- PLY

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool parsePlyType(const std::string& name, PlyType& type) {
    static const std::pair<const char*, PlyType> table[] = {
        {"char", PlyType::Int8},     {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
        {"uint8", PlyType::UInt8},   {"short", PlyType::Int16},     {"int16", PlyType::Int16},
        {"ushort", PlyType::UInt16}, {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
        {"int32", PlyType::Int32},   {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
        {"float", PlyType::Float32}, {"float32", PlyType::Float32}, {"double", PlyType::Float64},
        {"float64", PlyType::Float64},
    };
    for (const auto& entry : table) {
        if (name == entry.first) {
            type = entry.second;
            return true;
        }
    }
    return false;
}

size_t plyTypeSize(PlyType t) {
    switch (t) {
        case PlyType::Int8: case PlyType::UInt8: return 1;
        case PlyType::Int16: case PlyType::UInt16: return 2;
        case PlyType::Int32: case PlyType::UInt32: case PlyType::Float32: return 4;
        case PlyType::Float64: return 8;
    }
    return 0;
}

bool isIntegerType(PlyType t) { return t != PlyType::Float32 && t != PlyType::Float64; }

struct PlyProperty {
    std::string name;
    bool isList = false;
    PlyType countType = PlyType::UInt8;  // lists only
    PlyType valueType = PlyType::Float32;
};

struct PlyElement {
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> properties;

    // Smallest number of bytes one entry can occupy in a binary file; bounds
    // reservations so a lying header cannot make us allocate gigabytes.
    size_t minBinaryBytes() const {
        size_t n = 0;
        for (const PlyProperty& p : properties) n += plyTypeSize(p.isList ? p.countType : p.valueType);
        return std::max<size_t>(n, 1);
    }
};

enum class PlyFormat { Ascii, BinaryLittleEndian, BinaryBigEndian };

struct PlyHeader {
    PlyFormat format = PlyFormat::Ascii;
    std::vector<PlyElement> elements;
    size_t dataOffset = 0;  // first byte after the end_header line
};

bool hostIsLittleEndian() {
    const uint16_t one = 1;
    unsigned char first;
    std::memcpy(&first, &one, 1);
    return first == 1;
}

std::vector<std::string> splitWords(const std::string& line) {
    std::istringstream ls(line);
    std::vector<std::string> words;
    for (std::string w; ls >> w;) words.push_back(w);
    return words;
}

PlyHeader parsePlyHeader(const std::string& data, const std::string& path) {
    auto bad = [&](const std::string& what) { return InputError(str(path, ": bad PLY header: ", what)); };
    PlyHeader header;
    size_t pos = 0;
    size_t lineNumber = 0;
    bool sawFormat = false;
    for (;;) {
        size_t eol = data.find('\n', pos);
        if (eol == std::string::npos) {
            throw bad(lineNumber == 0 ? std::string("file is empty or has no line break after 'ply'")
                                      : std::string("missing 'end_header'"));
        }
        std::string line = data.substr(pos, eol - pos);
        if (!line.empty() && line.back() == '\r') line.pop_back();
        pos = eol + 1;
        ++lineNumber;
        std::vector<std::string> w = splitWords(line);
        if (lineNumber == 1) {
            if (w.size() != 1 || w[0] != "ply") throw bad("first line must be 'ply' (not a PLY file?)");
            continue;
        }
        if (w.empty()) continue;
        const std::string& key = w[0];
        auto where = [&](const std::string& what) { return bad(str("line ", lineNumber, ": ", what)); };
        if (key == "comment" || key == "obj_info") continue;
        if (key == "end_header") break;
        if (key == "format") {
            if (w.size() != 3) throw where("expected 'format <type> 1.0'");
            if (w[1] == "ascii") header.format = PlyFormat::Ascii;
            else if (w[1] == "binary_little_endian") header.format = PlyFormat::BinaryLittleEndian;
            else if (w[1] == "binary_big_endian") header.format = PlyFormat::BinaryBigEndian;
            else throw where(str("unknown format '", w[1], "'"));
            if (w[2] != "1.0" && w[2] != "1") throw where(str("unsupported version '", w[2], "'"));
            sawFormat = true;
        } else if (key == "element") {
            if (w.size() != 3) throw where("expected 'element <name> <count>'");
            PlyElement e;
            e.name = w[1];
            auto r = std::from_chars(w[2].data(), w[2].data() + w[2].size(), e.count);
            if (r.ec != std::errc() || r.ptr != w[2].data() + w[2].size()) {
                throw where(str("bad element count '", w[2], "'"));
            }
            header.elements.push_back(e);
        } else if (key == "property") {
            if (header.elements.empty()) throw where("property before any element");
            PlyProperty p;
            if (w.size() == 5 && w[1] == "list") {
                p.isList = true;
                if (!parsePlyType(w[2], p.countType)) throw where(str("unknown list count type '", w[2], "'"));
                if (!isIntegerType(p.countType)) throw where(str("list count type '", w[2], "' is not an integer"));
                if (!parsePlyType(w[3], p.valueType)) throw where(str("unknown property type '", w[3], "'"));
                p.name = w[4];
            } else if (w.size() == 3 && w[1] != "list") {
                if (!parsePlyType(w[1], p.valueType)) throw where(str("unknown property type '", w[1], "'"));
                p.name = w[2];
            } else {
                throw where("expected 'property <type> <name>' or 'property list <count> <type> <name>'");
            }
            header.elements.back().properties.push_back(p);
        } else {
            throw where(str("unknown keyword '", key, "'"));
        }
    }
    if (!sawFormat) throw bad("missing 'format' line");
    header.dataOffset = pos;
    return header;
}

// Reads typed values from the body in either encoding; every read is bounds
// checked so truncated files fail with the element and entry that ran short.
class PlyReader {
public:
    PlyReader(const std::string& data, size_t offset, PlyFormat format, const std::string& path)
        : mData(data), mPos(offset), mFormat(format), mPath(path),
          mSwap(format != PlyFormat::Ascii && (format == PlyFormat::BinaryLittleEndian) != hostIsLittleEndian()) {}

    void setLocation(const PlyElement& element, uint64_t entry) {
        mElement = &element;
        mEntry = entry;
    }

    size_t remainingBytes() const { return mData.size() - mPos; }

    double read(PlyType type) {
        if (mFormat == PlyFormat::Ascii) return readAscii(type);
        size_t n = plyTypeSize(type);
        if (remainingBytes() < n) throw truncated();
        unsigned char b[8];
        std::memcpy(b, mData.data() + mPos, n);
        mPos += n;
        if (mSwap) std::reverse(b, b + n);
        switch (type) {
            case PlyType::Int8: return double(fromBytes<int8_t>(b));
            case PlyType::UInt8: return double(fromBytes<uint8_t>(b));
            case PlyType::Int16: return double(fromBytes<int16_t>(b));
            case PlyType::UInt16: return double(fromBytes<uint16_t>(b));
            case PlyType::Int32: return double(fromBytes<int32_t>(b));
            case PlyType::UInt32: return double(fromBytes<uint32_t>(b));
            case PlyType::Float32: return double(fromBytes<float>(b));
            case PlyType::Float64: return fromBytes<double>(b);
        }
        return 0;
    }

    // Integer-typed values (list counts, indices); ASCII may hold anything.
    int64_t readInteger(PlyType type, const char* what) {
        double v = read(type);
        // 2^53: beyond that doubles skip integers; no sane mesh gets near it.
        if (!(std::fabs(v) <= 9007199254740992.0) || v != std::floor(v)) {
            throw InputError(str(mPath, ": ", what, " '", v, "' is not an integer", location()));
        }
        return int64_t(v);
    }

    uint64_t readListCount(PlyType countType, PlyType valueType) {
        int64_t n = readInteger(countType, "list length");
        if (n < 0) throw InputError(str(mPath, ": negative list length ", n, location()));
        if (mFormat != PlyFormat::Ascii && uint64_t(n) > remainingBytes() / plyTypeSize(valueType)) throw truncated();
        return uint64_t(n);
    }

    void skip(PlyType type, uint64_t count) {
        if (mFormat == PlyFormat::Ascii) {
            for (uint64_t i = 0; i < count; ++i) nextToken();
            return;
        }
        size_t n = plyTypeSize(type);
        if (count > remainingBytes() / n) throw truncated();
        mPos += size_t(count) * n;
    }

    void skipProperty(const PlyProperty& p) {
        if (p.isList) skip(p.valueType, readListCount(p.countType, p.valueType));
        else skip(p.valueType, 1);
    }

private:
    template <typename T>
    static T fromBytes(const unsigned char* b) {
        T v;
        std::memcpy(&v, b, sizeof(T));
        return v;
    }

    static bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

    std::string location() const {
        return mElement ? str(" (element '", mElement->name, "', entry ", mEntry, " of ", mElement->count, ")")
                        : std::string();
    }

    InputError truncated() const { return InputError(str(mPath, ": truncated PLY data", location())); }

    std::pair<const char*, const char*> nextToken() {
        while (mPos < mData.size() && isSpace(mData[mPos])) ++mPos;
        if (mPos >= mData.size()) throw truncated();
        size_t start = mPos;
        while (mPos < mData.size() && !isSpace(mData[mPos])) ++mPos;
        return {mData.data() + start, mData.data() + mPos};
    }

    double readAscii(PlyType) {
        auto [first, last] = nextToken();
        const char* begin = (*first == '+') ? first + 1 : first;  // from_chars rejects a leading '+'
        double v = 0;
        // from_chars: locale independent, unlike strtod.
        auto r = std::from_chars(begin, last, v);
        if (r.ec == std::errc::result_out_of_range) {
            v = (*begin == '-') ? -HUGE_VAL : HUGE_VAL;  // caught as non-finite by the caller
        } else if (r.ec != std::errc() || r.ptr != last) {
            throw InputError(str(mPath, ": bad number '", std::string(first, last), "' in PLY data", location()));
        }
        return v;
    }

    const std::string& mData;
    size_t mPos;
    PlyFormat mFormat;
    const std::string& mPath;
    bool mSwap;
    const PlyElement* mElement = nullptr;
    uint64_t mEntry = 0;
};

TriangleMesh loadPly(const std::string& path) {
    std::string data = readWholeFile(path);
    PlyHeader header = parsePlyHeader(data, path);

    const PlyElement* vertexElement = nullptr;
    const PlyElement* faceElement = nullptr;
    int xyz[3] = {-1, -1, -1};
    int faceList = -1;
    for (const PlyElement& e : header.elements) {
        if (e.name == "vertex") {
            if (vertexElement) throw InputError(str(path, ": bad PLY header: more than one 'vertex' element"));
            vertexElement = &e;
            for (size_t i = 0; i < e.properties.size(); ++i) {
                const PlyProperty& p = e.properties[i];
                int axis = p.name == "x" ? 0 : p.name == "y" ? 1 : p.name == "z" ? 2 : -1;
                if (axis < 0) continue;
                if (p.isList) throw InputError(str(path, ": bad PLY header: vertex property '", p.name, "' is a list"));
                xyz[axis] = int(i);
            }
        } else if (e.name == "face") {
            if (faceElement) throw InputError(str(path, ": bad PLY header: more than one 'face' element"));
            faceElement = &e;
            for (size_t i = 0; i < e.properties.size(); ++i) {
                const PlyProperty& p = e.properties[i];
                if (p.name != "vertex_indices" && p.name != "vertex_index") continue;
                if (!p.isList) {
                    throw InputError(str(path, ": bad PLY header: face property '", p.name, "' is not a list"));
                }
                if (!isIntegerType(p.valueType)) {
                    throw InputError(str(path, ": bad PLY header: face property '", p.name,
                                         "' has non-integer indices"));
                }
                if (faceList < 0) faceList = int(i);
            }
        }
    }
    if (!vertexElement) throw InputError(str(path, ": bad PLY header: no 'vertex' element"));
    for (int a = 0; a < 3; ++a) {
        if (xyz[a] < 0) {
            throw InputError(str(path, ": bad PLY header: vertex element lacks property '", "xyz"[a], "'"));
        }
    }
    if (vertexElement->count > UINT32_MAX) {
        throw InputError(str(path, ": ", vertexElement->count, " vertices exceed the 32-bit index range"));
    }
    if (!faceElement || faceElement->count == 0) throw InputError(str(path, ": mesh has no faces (point cloud?)"));
    if (faceList < 0) {
        throw InputError(str(path, ": bad PLY header: face element lacks a 'vertex_indices' list property"));
    }

    // Vertex roles per property index: 0..2 = coordinate, -1 = skipped.
    std::vector<int> role(vertexElement->properties.size(), -1);
    for (int a = 0; a < 3; ++a) role[size_t(xyz[a])] = a;

    PlyReader reader(data, header.dataOffset, header.format, path);
    TriangleMesh mesh;
    std::vector<int64_t> polyIndices;
    std::vector<uint64_t> polySizes;
    for (const PlyElement& e : header.elements) {
        // ASCII needs at least two characters per value, binary the element's
        // minimum size; either way this caps what a bogus count reserves.
        size_t fit = reader.remainingBytes() / (header.format == PlyFormat::Ascii ? 2 : e.minBinaryBytes());
        size_t reserve = size_t(std::min<uint64_t>(e.count, fit));
        if (&e == vertexElement) {
            mesh.positions.reserve(reserve);
            for (uint64_t i = 0; i < e.count; ++i) {
                reader.setLocation(e, i);
                double c[3] = {0, 0, 0};
                for (size_t k = 0; k < e.properties.size(); ++k) {
                    if (role[k] >= 0) c[role[k]] = reader.read(e.properties[k].valueType);
                    else reader.skipProperty(e.properties[k]);
                }
                // Checked in double: converting an out-of-range double to
                // float is undefined behaviour.
                for (double v : c) {
                    if (!(std::fabs(v) <= double(FLT_MAX))) {
                        throw InputError(str(path, ": vertex ", i, " has a non-finite or out-of-range coordinate (",
                                             c[0], ", ", c[1], ", ", c[2], ")"));
                    }
                }
                mesh.positions.emplace_back(float(c[0]), float(c[1]), float(c[2]));
            }
        } else if (&e == faceElement) {
            polySizes.reserve(reserve);
            polyIndices.reserve(reserve * 3);
            for (uint64_t i = 0; i < e.count; ++i) {
                reader.setLocation(e, i);
                for (size_t k = 0; k < e.properties.size(); ++k) {
                    const PlyProperty& p = e.properties[k];
                    if (int(k) != faceList) {
                        reader.skipProperty(p);
                        continue;
                    }
                    uint64_t n = reader.readListCount(p.countType, p.valueType);
                    for (uint64_t j = 0; j < n; ++j) polyIndices.push_back(reader.readInteger(p.valueType, "vertex index"));
                    polySizes.push_back(n);
                }
            }
        } else {
            // Edges, materials, anything else: walk past it entry by entry
            // (list properties make the size unknowable up front).
            for (uint64_t i = 0; i < e.count; ++i) {
                reader.setLocation(e, i);
                for (const PlyProperty& p : e.properties) reader.skipProperty(p);
            }
        }
    }

    // Faces are assembled last: the vertex element may follow the faces.
    size_t offset = 0, dropped = 0;
    mesh.indices.reserve(polyIndices.size());
    for (size_t f = 0; f < polySizes.size(); ++f) {
        appendPolygon(mesh, polyIndices.data() + offset, size_t(polySizes[f]), f, 0, path, dropped);
        offset += size_t(polySizes[f]);
    }
    finishMesh(mesh, path, dropped);
    return mesh;
}

}  // namespace

TriangleMesh loadMesh(const std::string& path) {
    std::string ext = extensionOf(path);
    if (ext == ".obj") return loadObj(path);
    if (ext == ".ply") return loadPly(path);
    throw InputError(str(path, ": unknown mesh file extension '", ext, "' (expected .obj or .ply)"));
}

}  // namespace vdbmarch
