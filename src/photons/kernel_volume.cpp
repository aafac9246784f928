#include "photons/kernel_volume.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/rng.h"
#include "core/sampling.h"

namespace vdbmarch {

namespace {

// The six axes and eight diagonals of a cube: a spread of directions whose
// mean of (min(d, r) / r)^3 is the volume fraction of the ball for
// a half-space at any orientation, once turned by a uniform rotation.
const Vec3 CubeDirections[KernelDirections] = {
    {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1},
    {0.57735027f, 0.57735027f, 0.57735027f},   {-0.57735027f, 0.57735027f, 0.57735027f},
    {0.57735027f, -0.57735027f, 0.57735027f},  {0.57735027f, 0.57735027f, -0.57735027f},
    {-0.57735027f, -0.57735027f, 0.57735027f}, {-0.57735027f, 0.57735027f, -0.57735027f},
    {0.57735027f, -0.57735027f, -0.57735027f}, {-0.57735027f, -0.57735027f, -0.57735027f}};

uint64_t bitsOf(const Vec3& x) {
    uint32_t b[3];
    std::memcpy(&b[0], &x.x, 4);
    std::memcpy(&b[1], &x.y, 4);
    std::memcpy(&b[2], &x.z, 4);
    return hashValues(b[0], b[1], b[2]);
}

}  // namespace

float kernelFractionInside(const Scene& scene, const Vec3& x, float radius) {
    if (scene.surfaces.empty() || !scene.surfaceSet || !(radius > 0) || !std::isfinite(radius)) return 1;
    Rng rng(bitsOf(x), 0x6b65726e656cULL);
    double sum = 0;
    // A uniform rotation: a uniform axis for z, a uniform angle about it.
    const Vec3 z = sampleUniformSphere(rng.uniform(), rng.uniform());
    Vec3 s, t;
    coordinateSystem(z, s, t);
    const float phi = 2 * Pi * rng.uniform(), c = std::cos(phi), sn = std::sin(phi);
    const Vec3 u = s * c + t * sn, v = t * c - s * sn;
    for (const Vec3& d : CubeDirections) {
        const Ray ray{x, normalize(u * d.x + v * d.y + z * d.z)};
        SurfaceHit h;
        const float reach = scene.surfaceSet->intersect(ray, 0.f, radius, h) ? std::min(h.t, radius) : radius;
        const double f = double(reach) / double(radius);
        sum += f * f * f;
    }
    return std::max(MinKernelFraction, float(sum / KernelDirections));
}

}  // namespace vdbmarch
