// Photon tracing (section 2.1, Jensen's volume photon map): photons leave
// every light, the background and emissive media in proportion to power,
// fly through the media by delta tracking against local majorants, refract
// and reflect at glass, and are stored at every real collision in a medium.
#pragma once

#include <cstdint>
#include <vector>

#include "photons/photon.h"
#include "photons/photon_emission.h"
#include "scene/scene.h"

namespace vdbmarch {

struct PhotonSet {
    std::vector<Photon> photons;
    size_t paths = 0;         // photon paths emitted (the N of the estimate)
    size_t directCount = 0;   // photons flagged Photon::Direct
    size_t causticCount = 0;  // photons flagged Photon::Caustic
    Color emittedPower{0, 0, 0};
    double seconds = 0;
};

// True when some medium scatters light: otherwise no photons are traced.
bool sceneScatters(const Scene& scene);

// Where photons can matter: the scattering media and the surfaces that may
// redirect light into them. For unbounded fog the box covers the scene's
// finite content (media, surfaces, lights, camera).
PhotonTarget photonTarget(const Scene& scene);

// Traces `paths` photon paths with the scene's max_depth (photons are stored
// after at most max_depth - 1 scattering events: the eye path's own
// scattering is the last one). Deterministic for (scene, paths, seed)
// whatever the thread count.
PhotonSet tracePhotons(const Scene& scene, size_t paths, uint64_t seed);

}  // namespace vdbmarch
