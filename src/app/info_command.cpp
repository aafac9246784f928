#include "app/info_command.h"

#include <cstdio>

#include "app/vdb_check.h"
#include "core/memory.h"
#include "volume/medium.h"

namespace vdbmarch {

int runInfo(const InfoArgs& a) {
    for (const auto& g : listVdbGrids(a.file)) std::printf("grid %s\n", g.c_str());
    VdbGridSummary s = summarizeVdb(a.file, "");
    std::printf("summary of '%s': %zu active voxels, voxel size %g, values [%g, %g] mean %g\n"
                "world bounds [%g %g %g] - [%g %g %g]\n",
                s.gridName.c_str(), s.activeVoxels, double(s.voxelSize), double(s.minValue), double(s.maxValue),
                double(s.meanValue), double(s.worldBounds.lo.x), double(s.worldBounds.lo.y), double(s.worldBounds.lo.z),
                double(s.worldBounds.hi.x), double(s.worldBounds.hi.y), double(s.worldBounds.hi.z));
    // What rendering it as a medium takes (docs/memory.md).
    MediumDesc medium;
    medium.type = MediumDesc::Type::Vdb;
    medium.file = a.file;
    medium.grid = s.gridName;
    const MediumMemory need = predictMediumMemory(medium);
    if (need.gridBytes > 0)
        std::printf("memory: grid %s; as a medium about %s while loading, %s once loaded (predicted)\n",
                    formatBytes(need.gridBytes).c_str(), formatBytes(need.loading).c_str(),
                    formatBytes(need.resident).c_str());
    return 0;
}

int runCheck(const CheckArgs& a) {
    int damaged = 0;
    for (const std::string& f : a.files) {
        if (a.inProcess) {
            const size_t voxels = readEveryGrid(f);  // throws: the message names the file
            if (!a.quiet) std::printf("%s: ok (%zu active voxels)\n", f.c_str(), voxels);
            continue;
        }
        try {
            checkVdbFileIsolated(f);
            if (!a.quiet) std::printf("%s: ok\n", f.c_str());
        } catch (const std::exception& e) {
            ++damaged;
            std::fprintf(stderr, "vdbmarch: error: %s\n", e.what());
        }
    }
    return damaged > 0 ? 1 : 0;
}

}  // namespace vdbmarch
