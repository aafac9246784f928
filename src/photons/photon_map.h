// The volume photon map: photons sorted along a Morton curve (so that
// neighbours are close in memory) and a nanoflann kd-tree over them for
// k-nearest-neighbour queries, with the in-scattered radiance estimate of
// eq. 4.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "photons/photon.h"

namespace vdbmarch {

class PhotonMap {
public:
    // Whether a query searches every photon, or only those of the query's
    // medium region (Photon::region): a gather near a glass surface must not
    // take photons from the other side, whose weights Phi / sigma_t belong
    // to another medium (a fog photon next to milk of 200x its extinction
    // counts 200x a milk photon).
    enum class Search { All, ByRegion };

    // Takes the photons (their weights already carry 1 / paths); builds the
    // tree, or one tree per region.
    explicit PhotonMap(std::vector<Photon> photons, Search search = Search::All);
    ~PhotonMap();
    PhotonMap(const PhotonMap&) = delete;
    PhotonMap& operator=(const PhotonMap&) = delete;

    size_t size() const { return mPhotons.size(); }
    const std::vector<Photon>& photons() const { return mPhotons; }
    const Photon& operator[](size_t i) const { return mPhotons[i]; }

    // The (up to) k photons nearest to x, nearest first (with
    // Search::ByRegion, among those of `region`): indices into photons() and
    // squared distances. Returns how many were found.
    size_t nearest(const Vec3& x, size_t k, uint32_t* indices, float* dist2, int region = 0) const;

    // Eq. 4: L_i(x, wo) = sum_p p(omega_p . wo) Phi_p / (sigma_t,p dV), over
    // the k nearest photons, dV the sphere that holds them. The weights of
    // stored photons are Phi_p / sigma_t(x_p); wo is the direction the light
    // leaves in (towards the viewer), `phase(cos)` the phase function (a
    // Color) with cos between a photon's travel direction and wo.
    // radiusScale < 1 (progressive passes, Knaus & Zwicker 2011) gathers only
    // the photons within radiusScale times that sphere's radius, over its
    // volume: given the k-th distance the k - 1 nearer photons are uniform in
    // the sphere where the density is, so the expectation is the same and
    // the kernel, hence the bias, is radiusScale times smaller (variance
    // grows as radiusScale^-3). `radius`, when given, receives the radius of
    // the gathering sphere. `region`: x's medium region (Search::ByRegion).
    template <typename Phase>
    Color estimateLi(const Vec3& x, const Vec3& wo, size_t k, Phase&& phase, float* radius = nullptr,
                     float radiusScale = 1, int region = 0) const {
        constexpr size_t MaxK = 1024;
        uint32_t idx[MaxK];
        float d2[MaxK];
        size_t n = nearest(x, k < MaxK ? k : MaxK, idx, d2, region);
        if (n == 0) return Color(0);
        // The farthest photon only sets the radius: summing the k - 1 inside
        // the sphere makes the estimate unbiased where photons are uniform
        // (docs/method.md).
        const float r2 = d2[n - 1] * radiusScale * radiusScale;
        Color sum(0);
        for (size_t i = 0; i + 1 < n; ++i) {
            if (radiusScale < 1 && d2[i] > r2) break;  // nearest first
            const Photon& p = mPhotons[idx[i]];
            sum += p.weight * phase(dot(p.travelDirection(), wo));
        }
        if (radius) *radius = std::sqrt(r2);
        if (!(r2 > 0)) return Color(0);
        return sum / (4.f / 3.f * Pi * r2 * std::sqrt(r2));
    }

    // Bytes held by the photons and the tree.
    size_t memoryBytes() const;

private:
    struct Tree;
    std::vector<Photon> mPhotons;  // by region (ByRegion), then along the Morton curve
    Search mSearch;
    // One tree over all photons (Search::All), or tree r over region r's
    // photons, null where a region has none.
    std::vector<std::unique_ptr<Tree>> mTrees;
};

}  // namespace vdbmarch
