// libFuzzer harness: the VDB loading path in-process (the grid extent check,
// then every grid read fully, as `vdbmarch check --in-process` does) and the
// radiance-cache reader (RadianceCache::load: the same path plus the
// cache's metadata checks). The first byte picks which. OpenVDB's own reader
// trusts sizes and compressed blocks, so this harness finds crashes inside
// OpenVDB: the commands never take them in-process (they read every VDB file
// in a child process first, app/vdb_check.h), and tools/fuzz.sh runs this
// harness with -fork and -ignore_crashes to count them rather than stop.
// A crash in our own code (the extent check, the cache's checks) is a bug.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "cache/radiance_cache.h"
#include "core/error.h"
#include "volume/medium.h"

using namespace vdbmarch;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 1) return 0;
    const std::string path = "/dev/shm/vdbmarch_fuzz_vdb_" + std::to_string(::getpid()) + ".vdb";
    FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) return 0;
    std::fwrite(data + 1, 1, size - 1, f);
    std::fclose(f);
    try {
        if (data[0] & 1) {
            RadianceCache c = RadianceCache::load(path);
            (void)c;
        } else {
            readEveryGrid(path);
        }
    } catch (const InputError&) {
    } catch (const IoError&) {
    }
    std::remove(path.c_str());
    return 0;
}
