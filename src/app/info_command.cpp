#include "app/info_command.h"

#include <cstdio>

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
    return 0;
}

}  // namespace vdbmarch
