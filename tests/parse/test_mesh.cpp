#include "parse/mesh.h"

#include "core/error.h"
#include "support/support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <type_traits>

namespace vdbmarch {
namespace {

namespace fs = std::filesystem;
using test::expectErrorContaining;

// Each test gets its own scratch directory, removed afterwards.
class MeshFiles : public ::testing::Test {
protected:
    std::string write(const std::string& name, const std::string& bytes) { return mDir.write(name, bytes); }
    test::TempDir mDir{"mesh"};
};

// loadMesh(path) throws exactly an E whose message contains every needle.
template <typename E>
void expectLoadError(const std::string& path, std::initializer_list<std::string> needles) {
    expectErrorContaining<E>([&] { loadMesh(path); }, needles);
}

// Writes PLY body values either as ASCII text or raw bytes in a given
// byte order, so one description produces all three encodings.
enum class Enc { Ascii, Little, Big };

class PlyBody {
public:
    explicit PlyBody(Enc enc) : mEnc(enc) {}
    template <typename T>
    PlyBody& put(T v) {
        if (mEnc == Enc::Ascii) {
            if constexpr (std::is_integral_v<T>) mOut << int64_t(v) << ' ';
            else mOut << v << ' ';
            return *this;
        }
        char b[sizeof(T)];
        std::memcpy(b, &v, sizeof(T));
        const uint16_t one = 1;
        char first;
        std::memcpy(&first, &one, 1);
        const bool hostLittle = first == 1;
        if ((mEnc == Enc::Little) != hostLittle) std::reverse(b, b + sizeof(T));
        mOut.write(b, sizeof(T));
        return *this;
    }
    PlyBody& endl() {
        if (mEnc == Enc::Ascii) mOut << '\n';
        return *this;
    }
    std::string str() const { return mOut.str(); }

private:
    Enc mEnc;
    std::ostringstream mOut;
};

const char* formatName(Enc enc) {
    return enc == Enc::Ascii ? "ascii" : enc == Enc::Little ? "binary_little_endian" : "binary_big_endian";
}

// An ASCII PLY of `vertices` float x, y, z and `faces` faces (uchar count,
// int indices), then `body`.
std::string asciiPly(int vertices, int faces, const std::string& body) {
    return str("ply\nformat ascii 1.0\nelement vertex ", vertices,
               "\nproperty float x\nproperty float y\nproperty float z\nelement face ", faces,
               "\nproperty list uchar int vertex_indices\nend_header\n", body);
}

// Five vertices, a triangle and a quad; x,y,z of three different types, and
// extra scalar/list properties and elements before and after to skip.
std::string richPly(Enc enc) {
    std::string header = std::string("ply\nformat ") + formatName(enc) +
                         " 1.0\n"
                         "comment written by test_mesh\n"
                         "obj_info nothing to see\n"
                         "element edge 2\n"
                         "property int vertex1\n"
                         "property int32 vertex2\n"
                         "property list uchar uchar tags\n"
                         "element vertex 5\n"
                         "property double x\n"
                         "property float y\n"
                         "property int16 z\n"
                         "property uchar red\n"
                         "property float confidence\n"
                         "property list uint8 int32 neighbours\n"
                         "property float64 intensity\n"
                         "element face 2\n"
                         "property uchar flags\n"
                         "property list int32 uint16 vertex_index\n"
                         "property list uchar float texcoord\n"
                         "element material 1\n"
                         "property list ushort char name\n"
                         "end_header\n";
    PlyBody b(enc);
    // edges
    b.put<int32_t>(0).put<int32_t>(1).put<uint8_t>(2).put<uint8_t>(7).put<uint8_t>(9).endl();
    b.put<int32_t>(1).put<int32_t>(2).put<uint8_t>(0).endl();
    // vertices: x y z red confidence neighbours... intensity
    const double xs[5] = {0.5, 1, -2.75, 3, 0.125};
    const float ys[5] = {-1.25f, 0, 4.5f, 1.5f, 2};
    const int16_t zs[5] = {0, 3, -7, 2, 5};
    for (int i = 0; i < 5; ++i) {
        b.put<double>(xs[i]).put<float>(ys[i]).put<int16_t>(zs[i]).put<uint8_t>(200).put<float>(0.75f);
        b.put<uint8_t>(uint8_t(i % 3));
        for (int k = 0; k < i % 3; ++k) b.put<int32_t>(k);
        b.put<double>(-3.5).endl();
    }
    // faces: flags, vertex_index list, texcoord list
    b.put<uint8_t>(1).put<int32_t>(3).put<uint16_t>(0).put<uint16_t>(1).put<uint16_t>(2);
    b.put<uint8_t>(6);
    for (int k = 0; k < 6; ++k) b.put<float>(0.5f);
    b.endl();
    b.put<uint8_t>(0).put<int32_t>(4).put<uint16_t>(1).put<uint16_t>(3).put<uint16_t>(4).put<uint16_t>(2);
    b.put<uint8_t>(0).endl();
    // material name "ab"
    b.put<uint16_t>(2).put<int8_t>('a').put<int8_t>('b').endl();
    return header + b.str();
}

// `m` has `count` vertices, vertex `i` at `p`, and these triangle indices.
void expectMesh(const TriangleMesh& m, size_t count, size_t i, const Vec3& p, const std::vector<uint32_t>& indices) {
    ASSERT_EQ(m.positions.size(), count);
    EXPECT_EQ(m.positions[i], p);
    EXPECT_EQ(m.indices, indices);
}

void expectRichMesh(const TriangleMesh& m) {
    const std::vector<Vec3> positions = {
        {0.5f, -1.25f, 0}, {1, 0, 3}, {-2.75f, 4.5f, -7}, {3, 1.5f, 2}, {0.125f, 2, 5}};
    ASSERT_EQ(m.positions.size(), positions.size());
    for (size_t i = 0; i < positions.size(); ++i) EXPECT_EQ(m.positions[i], positions[i]) << "vertex " << i;
    // The quad (1,3,4,2) is fanned around its first vertex.
    const std::vector<uint32_t> indices = {0, 1, 2, 1, 3, 4, 1, 4, 2};
    EXPECT_EQ(m.indices, indices);
    EXPECT_EQ(m.triangleCount(), 3u);
}

TEST_F(MeshFiles, PlyAsciiWithExtraPropertiesAndElements) {
    expectRichMesh(loadMesh(write("rich.ply", richPly(Enc::Ascii))));
}

TEST_F(MeshFiles, PlyBinaryLittleEndian) {
    expectRichMesh(loadMesh(write("rich.ply", richPly(Enc::Little))));
}

TEST_F(MeshFiles, PlyBinaryBigEndian) {
    expectRichMesh(loadMesh(write("rich.ply", richPly(Enc::Big))));
}

TEST_F(MeshFiles, PlyUppercaseExtensionAndCrlfHeader) {
    // Stanford-style bunny layout (confidence/intensity), Windows line ends.
    std::string text =
        "ply\r\nformat ascii 1.0\r\nelement vertex 4\r\nproperty float x\r\nproperty float y\r\n"
        "property float z\r\nproperty float confidence\r\nproperty float intensity\r\n"
        "element face 2\r\nproperty list uchar int vertex_indices\r\nend_header\r\n"
        "0 0 0 1 0.5\r\n1 0 0 1 0.5\r\n1 1 0 1 0.5\r\n0 1 0 1 0.5\r\n3 0 1 2\r\n3 0 2 3\r\n";
    expectMesh(loadMesh(write("quad.PLY", text)), 4, 2, Vec3(1, 1, 0), {0, 1, 2, 0, 2, 3});
}

TEST_F(MeshFiles, PlyVertexElementAfterFaces) {
    std::string text =
        "ply\nformat ascii 1.0\nelement face 1\nproperty list uint uint vertex_indices\n"
        "element vertex 3\nproperty uchar x\nproperty char y\nproperty ushort z\nend_header\n"
        "3 2 1 0\n1 2 3\n4 -5 6\n7 8 9\n";
    expectMesh(loadMesh(write("late.ply", text)), 3, 1, Vec3(4, -5, 6), {2, 1, 0});
}

TEST_F(MeshFiles, DegenerateTrianglesAreDropped) {
    setWarningsQuiet(true);
    int before = warningCount();
    std::string text = asciiPly(3, 3, "0 0 0\n1 0 0\n0 1 0\n3 0 0 1\n3 0 1 2\n2 0 1\n");
    TriangleMesh m = loadMesh(write("degenerate.ply", text));
    EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2}));
    EXPECT_EQ(warningCount(), before + 1);  // one summary warning, not one per face
    setWarningsQuiet(false);
}

TEST_F(MeshFiles, ObjShapesMergedAndPolygonsTriangulated) {
    std::string text =
        "# two objects sharing one vertex list\n"
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 2.5\n"
        "vt 0 0\nvn 0 0 1\n"
        "o first\nf 1/1/1 2/1/1 3/1/1 4/1/1\n"
        "o second\nf -5 -4 -1\n"
        "g third\nf 2//1 3//1 5//1\n";
    expectMesh(loadMesh(write("shapes.OBJ", text)), 5, 4, Vec3(0, 0, 2.5f), {0, 1, 2, 0, 2, 3, 0, 1, 4, 1, 2, 4});
}

TEST_F(MeshFiles, ObjIndexOutOfRange) {
    std::string path = write("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    expectLoadError<InputError>(path, {path, "9", "3 vertices"});
}

TEST_F(MeshFiles, PlyIndexOutOfRange) {
    std::string path = write("range.ply", asciiPly(4, 1, "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 7 1\n"));
    expectLoadError<InputError>(path, {path, "index 7", "4 vertices"});
}

TEST_F(MeshFiles, NegativePlyIndexIsOutOfRange) {
    std::string path = write("negative.ply", asciiPly(3, 1, "0 0 0\n1 0 0\n0 1 0\n3 0 -1 1\n"));
    expectLoadError<InputError>(path, {"-1", "3 vertices"});
}

TEST_F(MeshFiles, MissingFile) {
    std::string path = mDir / "nope.ply";
    expectLoadError<IoError>(path, {path});
    std::string objPath = mDir / "nope.obj";
    expectLoadError<IoError>(objPath, {objPath});
}

TEST_F(MeshFiles, UnknownExtension) {
    std::string path = write("mesh.stl", "solid x\n");
    expectLoadError<InputError>(path, {path, ".stl"});
    std::string noExt = write("mesh", "ply\n");
    expectLoadError<InputError>(noExt, {noExt});
}

TEST_F(MeshFiles, BadHeaders) {
    const std::string tail =
        "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    struct Case {
        std::string text, needle;
    };
    const Case cases[] = {
        {"plx\nformat ascii 1.0\n" + tail, "first line"},
        {"ply\nformat ascii 2.0\n" + tail, "version"},
        {"ply\nformat utf8 1.0\n" + tail, "unknown format"},
        {"ply\n" + tail, "format"},
        {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float16 x\n", "float16"},
        {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n", "end_header"},
        {"ply\nformat ascii 1.0\nelement vertex many\n" + tail, "many"},
        {"ply\nformat ascii 1.0\nproperty float x\n" + tail, "before any element"},
        {"ply\nformat ascii 1.0\nelement face 1\nproperty list float int vertex_indices\nend_header\n",
         "not an integer"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
         "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0\n3 0 0 0\n",
         "'z'"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
         "element face 1\nproperty list uchar int corners\nend_header\n0 0 0\n3 0 0 0\n",
         "vertex_indices"},
        {"", "empty"},
    };
    for (const Case& c : cases) {
        std::string path = write("header.ply", c.text);
        SCOPED_TRACE(c.text);
        expectLoadError<InputError>(path, {path, c.needle});
    }
}

TEST_F(MeshFiles, TruncatedBinary) {
    const std::string full = richPly(Enc::Little);
    // Cut inside the vertices and inside the faces: both must be caught.
    for (size_t cut : {size_t(40), size_t(150)}) {
        std::string path = write("cut.ply", full.substr(0, full.size() - cut));
        SCOPED_TRACE(cut);
        expectLoadError<InputError>(path, {path, "truncated"});
    }
    const std::string bigEndian = richPly(Enc::Big);
    std::string path = write("cut_be.ply", bigEndian.substr(0, bigEndian.size() - 1));
    expectLoadError<InputError>(path, {"truncated", "material"});
}

TEST_F(MeshFiles, TruncatedInSkippedTrailingElement) {
    std::string header =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
        "element extra 1\nproperty double weight\nend_header\n";
    PlyBody b(Enc::Little);
    for (float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) b.put<float>(v);
    b.put<uint8_t>(3).put<int32_t>(0).put<int32_t>(1).put<int32_t>(2).put<double>(1.5);
    const std::string full = header + b.str();
    EXPECT_EQ(loadMesh(write("whole.ply", full)).triangleCount(), 1u);
    std::string path = write("cut.ply", full.substr(0, full.size() - 3));
    expectLoadError<InputError>(path, {path, "truncated", "extra"});
}

TEST_F(MeshFiles, DirectoryIsAnIoError) {
    std::string path = mDir / "folder.ply";
    fs::create_directories(path);
    expectLoadError<IoError>(path, {path});
}

TEST_F(MeshFiles, TruncatedAscii) {
    std::string path = write("cut.ply", asciiPly(3, 1, "0 0 0\n1 0 0\n0 1 0\n3 0 1\n"));
    expectLoadError<InputError>(path, {path, "truncated", "face"});
}

TEST_F(MeshFiles, NonFiniteCoordinates) {
    std::string text = asciiPly(3, 1, "0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n");
    std::string path = write("nan.ply", text);
    expectLoadError<InputError>(path, {path, "vertex 1", "non-finite"});

    // A double beyond float range cannot be stored either.
    std::string big = text;
    big.replace(big.find("1 nan 0"), 7, "1 1e300 0");
    std::string bigPath = write("big.ply", big);
    expectLoadError<InputError>(bigPath, {"vertex 1"});

    std::string objPath = write("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 1 1e999\nf 1 2 3\n");
    expectLoadError<InputError>(objPath, {objPath, "vertex 2", "non-finite"});
}

TEST_F(MeshFiles, ZeroTriangles) {
    setWarningsQuiet(true);
    std::string path = write("flat.ply", asciiPly(3, 1, "0 0 0\n1 0 0\n0 1 0\n3 0 1 1\n"));
    expectLoadError<InputError>(path, {path, "no"});
    std::string objPath = write("points.obj", "v 0 0 0\nv 1 0 0\n");
    expectLoadError<InputError>(objPath, {objPath, "no"});
    setWarningsQuiet(false);
}

// ---------------------------------------------------------------- topology

TEST(MeshTopology, UnitBoxIsClosedOutwardAndUnitVolume) {
    TriangleMesh box = makeUnitBox();
    EXPECT_EQ(box.positions.size(), 8u);
    EXPECT_EQ(box.triangleCount(), 12u);
    EXPECT_DOUBLE_EQ(signedVolume(box), 1.0);
    EXPECT_TRUE(isClosed(box));
    // Every triangle has area 1/2 and faces away from the centre.
    for (size_t t = 0; t < box.triangleCount(); ++t) {
        Vec3 a = box.positions[box.indices[3 * t]], b = box.positions[box.indices[3 * t + 1]],
             c = box.positions[box.indices[3 * t + 2]];
        Vec3 n = cross(b - a, c - a);
        EXPECT_FLOAT_EQ(length(n), 1.f) << "triangle " << t;
        EXPECT_GT(dot(n, (a + b + c) / 3.f), 0.f) << "triangle " << t;
    }
}

TEST(MeshTopology, FlipAndOrientOutward) {
    TriangleMesh box = makeUnitBox();
    flipWinding(box);
    EXPECT_DOUBLE_EQ(signedVolume(box), -1.0);
    EXPECT_TRUE(isClosed(box));
    orientOutward(box);
    EXPECT_DOUBLE_EQ(signedVolume(box), 1.0);
    EXPECT_EQ(box.indices, makeUnitBox().indices);
    orientOutward(box);  // already outward: untouched
    EXPECT_EQ(box.indices, makeUnitBox().indices);
}

TEST(MeshTopology, OpenAndNonManifoldMeshesAreNotClosed) {
    TriangleMesh open = makeUnitBox();
    open.indices.resize(open.indices.size() - 3);
    EXPECT_FALSE(isClosed(open));

    // A repeated triangle makes three edges shared by three triangles.
    TriangleMesh extra = makeUnitBox();
    extra.indices.insert(extra.indices.end(), extra.indices.begin(), extra.indices.begin() + 3);
    EXPECT_FALSE(isClosed(extra));

    EXPECT_FALSE(isClosed(TriangleMesh{}));
}

TEST(MeshTopology, DuplicatedVerticesAreWeldedForClosure) {
    // What OBJ/PLY exporters with per-face vertices produce: 36 vertices.
    TriangleMesh box = makeUnitBox();
    TriangleMesh soup;
    for (uint32_t i : box.indices) {
        soup.indices.push_back(uint32_t(soup.positions.size()));
        soup.positions.push_back(box.positions[i]);
    }
    EXPECT_EQ(soup.positions.size(), 36u);
    EXPECT_TRUE(isClosed(soup));
    EXPECT_DOUBLE_EQ(signedVolume(soup), 1.0);
}

TEST(MeshTopology, TransformKeepsFrontOutward) {
    TriangleMesh box = makeUnitBox();
    transformMesh(box, [](const Vec3& p) { return Vec3(2 * p.x, 3 * p.y, 4 * p.z) + Vec3(10, -5, 7); });
    EXPECT_DOUBLE_EQ(signedVolume(box), 24.0);
    EXPECT_EQ(box.indices, makeUnitBox().indices);
    EXPECT_EQ(box.positions[7], Vec3(11, -3.5f, 9));

    // A mirror flips the winding back so the volume stays positive.
    TriangleMesh mirrored = makeUnitBox();
    transformMesh(mirrored, [](const Vec3& p) { return Vec3(-p.x, p.y, 2 * p.z); });
    EXPECT_DOUBLE_EQ(signedVolume(mirrored), 2.0);
    EXPECT_NE(mirrored.indices, makeUnitBox().indices);
    EXPECT_EQ(mirrored.positions[1], Vec3(-0.5f, -0.5f, -1.f));

    // Open, flat meshes have no meaningful volume, yet their front must still
    // follow the transform: the -x face of the box (normal -x) stays facing
    // -x under a translation and under a mirror in y.
    auto firstNormal = [](const TriangleMesh& m) {
        Vec3 a = m.positions[m.indices[0]], b = m.positions[m.indices[1]], c = m.positions[m.indices[2]];
        return normalize(cross(b - a, c - a));
    };
    TriangleMesh face = makeUnitBox();
    face.indices.resize(6);
    ASSERT_EQ(firstNormal(face), Vec3(-1, 0, 0));
    const auto indices = face.indices;
    transformMesh(face, [](const Vec3& p) { return p + Vec3(5, 0, 0); });
    EXPECT_EQ(face.indices, indices);
    EXPECT_EQ(firstNormal(face), Vec3(-1, 0, 0));
    transformMesh(face, [](const Vec3& p) { return Vec3(p.x, -p.y, p.z); });
    EXPECT_NE(face.indices, indices);
    EXPECT_EQ(firstNormal(face), Vec3(-1, 0, 0));
}

TEST(MeshAssets, StanfordBunnyRes2) {
    const std::string path = test::assetPath("bun_zipper_res2.ply");
    if (!fs::exists(path)) GTEST_SKIP() << "asset not present: " << path;
    TriangleMesh bunny = loadMesh(path);
    EXPECT_EQ(bunny.positions.size(), 8171u);
    EXPECT_EQ(bunny.triangleCount(), 16301u);
    EXPECT_FALSE(isClosed(bunny));  // the scan has holes in its base
    for (const Vec3& p : bunny.positions) ASSERT_TRUE(isFinite(p));
}

}  // namespace
}  // namespace vdbmarch
