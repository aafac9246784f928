// The estimators a scene can ask for (render.method) and where the marchers
// take L_i from (render.li), with the names the scene file and the command
// line spell them.
#pragma once

#include <string>
#include <vector>

namespace vdbmarch {

enum class Method { Uniform, Transmittance, Guided, Reference };
enum class LiSource {
    // Shadow rays for direct light plus a continuation path (delta tracking,
    // next-event estimation at every vertex) for the rest; photons only for
    // what paths cannot find (caustics of delta lights through glass).
    // Unbiased for everything else: the default.
    Path,
    Photons,  // shadow rays for direct light plus the photon map's non-direct photons (the paper's eq. 4)
    Cache,    // the radiance cache alone: a fast, biased preview
};

// The path tracer: every path is traced by the path loop, so render.li does
// not apply.
inline bool isPathTracer(Method m) { return m == Method::Reference; }

// Every method, in the order `--method` lists them.
const std::vector<Method>& allMethods();
const char* methodName(Method m);
// False for an unknown name.
bool parseMethod(const std::string& name, Method& out);
// "uniform, transmittance, ..." for messages and help.
std::string methodList();

const char* liSourceName(LiSource s);
bool parseLiSource(const std::string& name, LiSource& out);

}  // namespace vdbmarch
