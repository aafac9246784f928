#include "app/inspect_command.h"

#include <cmath>
#include <cstdio>

#include "app/command_line.h"
#include "app/vdb_check.h"
#include "cache/cache_inspect.h"
#include "core/atomic_file.h"

namespace vdbmarch {

namespace {

Vec3 parseDirection(const std::string& text) {
    float x, y, z;
    char extra;
    if (std::sscanf(text.c_str(), "%f,%f,%f%c", &x, &y, &z, &extra) != 3 || !std::isfinite(x) || !std::isfinite(y) ||
        !std::isfinite(z) || x * x + y * y + z * z == 0)
        throw InputError(str("--direction ", text, ": expected a non-zero vector x,y,z"));
    return normalize(Vec3(x, y, z));
}

}  // namespace

int runInspect(const InspectArgs& a) {
    checkVdbFilesIsolated({a.input});
    RadianceCache c = RadianceCache::load(a.input);
    if (a.slice.empty() && a.direction.empty()) {
        if (!a.output.empty()) throw InputError("-o needs --direction (a .vdb of L_i) or --slice (a .png)");
        std::printf("%s", cacheSummary(c).c_str());
        return 0;
    }
    if (a.output.empty()) throw InputError("--direction and --slice write a file: give -o");
    Vec3 wo(0);
    if (!a.direction.empty()) wo = parseDirection(a.direction);
    if (!a.slice.empty()) {
        if (!endsWith(a.output, ".png")) throw InputError(str("-o ", a.output, ": a slice is written as .png"));
        char axisName = 0, extra;
        float value;
        if (std::sscanf(a.slice.c_str(), "%c=%f%c", &axisName, &value, &extra) != 2 ||
            (axisName != 'x' && axisName != 'y' && axisName != 'z') || !std::isfinite(value))
            throw InputError(str("--slice ", a.slice, ": expected x=VALUE, y=VALUE or z=VALUE (world units)"));
        checkWritable(a.output);
        float maxL = writeCacheSlice(c, axisName - 'x', value, wo, a.output);
        std::printf("slice %s: L_i %s, log scale from %g to %g (4 decades), black = no cell -> %s\n", a.slice.c_str(),
                    a.direction.empty() ? "averaged over directions" : ("towards " + a.direction).c_str(),
                    double(maxL) * 1e-4, double(maxL), a.output.c_str());
        return 0;
    }
    if (!endsWith(a.output, ".vdb")) throw InputError(str("-o ", a.output, ": L_i for a direction is written as .vdb"));
    checkWritable(a.output);
    c.saveDirectional(a.output, wo);
    std::printf("wrote L_i towards %s as float grid(s) 'Li%s' -> %s\n", a.direction.c_str(),
                c.levels > 1 ? "_level<n>" : "", a.output.c_str());
    return 0;
}

}  // namespace vdbmarch
