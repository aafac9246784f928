// libFuzzer harness: the OBJ (tinyobjloader) and PLY (our parser) readers.
// The first byte picks the format; the rest is the file. InputError and
// IoError are the only allowed outcomes besides a mesh. Built by
// tools/fuzz.sh.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "core/error.h"
#include "parse/mesh.h"

using namespace vdbmarch;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 1) return 0;
    const std::string ext = (data[0] & 1) ? ".ply" : ".obj";
    const std::string path = "/dev/shm/vdbmarch_fuzz_mesh_" + std::to_string(::getpid()) + ext;
    FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) return 0;
    std::fwrite(data + 1, 1, size - 1, f);
    std::fclose(f);
    try {
        TriangleMesh m = loadMesh(path);
        for (uint32_t i : m.indices)
            if (i >= m.positions.size()) __builtin_trap();  // an index past the vertices is a bug
    } catch (const InputError&) {
    } catch (const IoError&) {
    }
    std::remove(path.c_str());
    return 0;
}
