// A piece of a ray with the extinction majorant sigma_maj over it, for every
// channel: a medium's density bound (volume/medium.h) times its
// sigma_t, summed over the region's media (tracking.h).
#pragma once

namespace vdbmarch {

struct MajorantSegment {
    float t0, t1, sigmaMaj;
};

}  // namespace vdbmarch
