// Building the radiance cache from a photon map: the grid resolution rule of
// section 3.1, the sparse topology from the media's active voxels, the
// octree-like subdivision by photon density of section 3.4, and the
// coefficients of eq. 27 at every cell centre.
#pragma once

#include <string>

#include "cache/radiance_cache.h"
#include "photons/photon_map.h"
#include "scene/scene.h"

namespace vdbmarch {

struct CacheBuildStats {
    double topologySeconds = 0, estimateSeconds = 0;
    size_t cells = 0;
};

// The SH order actually stored: 0 when every scattering medium is
// isotropic (eq. 26 gives w'_l = 0 for l > 0), else settings.shOrder.
int effectiveShOrder(const Scene& scene, int requested);

// Uniform cell size by s = (a N / (k V))^(1/3), with V the volume of the
// cells that hold scattering media (the paper's bounding box w_x w_y w_z
// where the medium fills it).
// k: photons per estimate (the scene's photons.k).
RadianceCache buildRadianceCache(const Scene& scene, const PhotonMap& photons, size_t paths,
                                 const CacheSettings& settings, int k, CacheBuildStats* stats = nullptr);

// Progressive refinement: eq. 27 from a fresh, independent photon batch on
// the cache's own cells, averaged with the info.batches estimates it holds
// (each batch's weights carry 1 / its paths, so every estimate is of the same
// L_i and the mean's variance falls as 1 / batches). The topology stays.
void refineRadianceCache(const Scene& scene, const PhotonMap& photons, size_t paths, int k, RadianceCache& cache);


}  // namespace vdbmarch
