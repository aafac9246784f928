// A short fuzz run inside the test suite (and so under the sanitizers in CI,
// tools/sanitize.sh): the project's own scene files and meshes, mutated at
// random (byte changes, insertions, deletions, cuts, splices; fixed seeds),
// through the scene parser (with a --set override) and the OBJ and PLY
// readers. The only allowed failures are InputError and IoError; any other
// exception fails the test, and a memory error stops it under ASan. The
// coverage-guided runs are tools/fuzz.sh (libFuzzer, clang); this one needs
// no extra compiler and takes seconds.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/error.h"
#include "core/rng.h"
#include "parse/mesh.h"
#include "parse/scene_desc.h"
#include "parse/scene_json.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using test::readBytes;
using test::samplePath;

// One to four random edits of `s`.
std::string mutate(const std::string& s, const std::vector<std::string>& corpus, Rng& rng) {
    std::string m = s;
    const int edits = 1 + int(rng.uniform() * 4);
    static const char* const tokens[] = {"{", "}", "[", "]", ",", ":", "\"", "-", "1e400", "-1", "0", "nan",
                                         "1e-45", "4294967296", "\n", " ", "\\u0000", "null", "true"};
    for (int e = 0; e < edits; ++e) {
        const size_t at = m.empty() ? 0 : size_t(rng.uniform() * double(m.size()));
        switch (int(rng.uniform() * 6)) {
            case 0:
                if (!m.empty()) m[at] = char(int(rng.uniform() * 256));
                break;
            case 1: m.insert(at, tokens[size_t(rng.uniform() * (sizeof tokens / sizeof tokens[0]))]); break;
            case 2: m.erase(at, size_t(rng.uniform() * 16)); break;
            case 3: m.resize(at); break;  // cut short
            case 4: {                     // splice from another file
                const std::string& o = corpus[size_t(rng.uniform() * double(corpus.size()))];
                const size_t from = size_t(rng.uniform() * double(o.size()));
                m.insert(at, o.substr(from, size_t(rng.uniform() * 64)));
                break;
            }
            default:
                if (!m.empty()) m.insert(at, std::string(1 + size_t(rng.uniform() * 8), m[at]));
        }
    }
    return m;
}

template <typename F>
void expectOnlyInputErrors(F&& f, const std::string& input) {
    try {
        f();
    } catch (const InputError&) {
    } catch (const IoError&) {
    } catch (const std::exception& e) {
        ADD_FAILURE() << "escaped as " << typeid(e).name() << ": " << e.what() << "\ninput: " << input.substr(0, 400);
    }
}

TEST(MutationFuzz, SceneParserRefusesOnlyWithInputErrors) {
    std::vector<std::string> corpus;
    for (const char* f : {"cloud.json", "glass.json", "plume.json", "sparse.json", "scenes/cloud_sun.json",
                          "scenes/exp1_point.json", "scenes/fig3b_spots.json", "scenes/fig4_caustic.json"})
        corpus.push_back(readBytes(samplePath(f)));
    ASSERT_FALSE(corpus[0].empty());
    const char* overrides[] = {"render.spp=2", "media.0.g=0.999", "camera.resolution=[0,0]", "lights.5.x=1",
                               "photons.alpha=2", "render.max_depth=-1"};
    Rng rng(0x66757a7a);
    const int runs = 30000;
    for (int i = 0; i < runs; ++i) {
        const std::string text = mutate(corpus[size_t(i) % corpus.size()], corpus, rng);
        const std::string set = overrides[size_t(rng.uniform() * 6)];
        expectOnlyInputErrors([&] { parseSceneText(text, "fuzz.json", {set}); }, text);
        if (HasFailure()) return;  // one report is enough
    }
}

TEST(MutationFuzz, MeshReadersRefuseOnlyWithInputErrors) {
    test::TempDir dir("mutation_fuzz");
    const std::string obj = readBytes(samplePath("scenes/knot.obj")).substr(0, 20000);
    const std::string ply =
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
        "3 0 1 2\n4 0 1 2 3\n";
    std::string binary = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                         "property float y\nproperty float z\nelement face 1\nproperty list uchar int "
                         "vertex_indices\nend_header\n";
    const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    binary.append(reinterpret_cast<const char*>(v), sizeof v);
    const unsigned char n = 3;
    const int idx[3] = {0, 1, 2};
    binary.append(reinterpret_cast<const char*>(&n), 1);
    binary.append(reinterpret_cast<const char*>(idx), sizeof idx);
    const std::vector<std::string> corpus = {obj, ply, binary};
    Rng rng(0x6d657368);
    for (int i = 0; i < 6000; ++i) {
        const size_t which = size_t(i) % corpus.size();
        const std::string bytes = mutate(corpus[which], corpus, rng);
        const std::string path = dir.path() + (which == 0 ? "/m.obj" : "/m.ply");
        test::writeText(path, bytes);
        expectOnlyInputErrors(
            [&] {
                TriangleMesh m = loadMesh(path);
                for (uint32_t k : m.indices) ASSERT_LT(k, m.positions.size());
            },
            bytes);
        if (HasFailure()) return;
    }
}

}  // namespace
}  // namespace vdbmarch
