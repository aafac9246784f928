// libFuzzer harness: EXR images as `compare` and `bench` read them
// (OpenEXR through readExr). InputError and IoError are the only allowed
// failures. Built by tools/fuzz.sh.
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "core/error.h"
#include "image/exr_io.h"

using namespace vdbmarch;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = "/dev/shm/vdbmarch_fuzz_exr_" + std::to_string(::getpid()) + ".exr";
    FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) return 0;
    std::fwrite(data, 1, size, f);
    std::fclose(f);
    try {
        Image img = readExr(path);
        if (img.rgba.size() != size_t(img.width) * size_t(img.height) * 4) __builtin_trap();
    } catch (const InputError&) {
    } catch (const IoError&) {
    }
    std::remove(path.c_str());
    return 0;
}
