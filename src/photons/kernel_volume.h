// The part of a photon gather's sphere that lies in the medium region of its
// centre. Photons land only in that region, so near its surface (the glass
// around a medium, where a camera path's first vertices gather) the k
// nearest photons fill less than the sphere, and eq. 4 over the whole
// sphere's volume reads low (docs/method.md, "The volume photon map").
#pragma once

#include "scene/scene.h"

namespace vdbmarch {

// The fraction of the ball of `radius` about x that x reaches without
// crossing a surface: mean over KernelDirections directions (a fixed
// spread, turned by a rotation drawn from x's bits) of (min(d, r) / r)^3,
// d the distance to the first surface that way. Exact in expectation where
// the region is star-shaped from x (a half-space, any convex glass);
// at least MinKernelFraction, which bounds the estimate's growth in slivers.
// 1 in a scene without surfaces.
float kernelFractionInside(const Scene& scene, const Vec3& x, float radius);

constexpr int KernelDirections = 14;
constexpr float MinKernelFraction = 1.f / KernelDirections;

}  // namespace vdbmarch
