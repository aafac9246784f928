// The directions of a cache cell's incident light as a few von Mises-Fisher
// lobes, fitted to the photons gathered at the cell (the same k nearest
// that eq. 27 projects), for product sampling of continuation directions
// (product_sampler.h). Beyond the paper: its SH expansion (eq. 27) is kept
// for L_i; the lobes only guide directions.
//
// A cell stores, per lobe, sufficient statistics that are linear in the
// photon weights: W = sum w, S = sum w wi (wi the direction a path takes to
// meet the photon's light, minus its travel direction) and N, the number of
// photons. Independent photon batches (progressive passes) therefore
// average like the SH coefficients, after their photons are assigned to the
// lobes already there. A lobe's mean direction is S / |S| and its
// concentration comes from the mean resultant length |S| / W (Banerjee et
// al. 2005), with the small-sample bias of |S| / W removed using N.
#pragma once

#include "core/math.h"

namespace vdbmarch {

// vMF(w; mu, kappa) = kappa / (2 pi (1 - e^{-2 kappa})) e^{kappa (mu.w - 1)},
// uniform (1 / 4 pi) as kappa -> 0.
struct VmfLobe {
    Vec3 mu{0, 0, 1};
    float kappa = 0;
    float weight = 0;  // share of the mixture
    float norm = Inv4Pi;  // kappa / (2 pi (1 - e^{-2 kappa})), set by make()

    static VmfLobe make(const Vec3& mu, float kappa, float weight);
    float pdf(const Vec3& w) const;
    // Two uniforms in [0, 1) to a direction (Jakob 2012, stable for large kappa).
    Vec3 sample(float u1, float u2) const;
    // log of the normalisation C(kappa) = kappa / (4 pi sinh kappa), so that
    // vMF(w) = C e^{kappa mu.w}; log(1 / 4 pi) at kappa = 0.
    static float logNormalisation(float kappa);
};

// A cell's lobes ready for products (direction_lobes' statistics read once
// per cache build, not at every path vertex): mean direction, concentration
// and log(W C(kappa)).
struct PreparedLobes {
    int count = 0;
    Vec3 mu[4];
    float kappa[4];
    float logWeightNorm[4];
};

struct DirectionLobes {
    static constexpr int MaxLobes = 4;
    static constexpr int LobeFloats = 5;  // W, S.x, S.y, S.z, N
    static constexpr int Floats = MaxLobes * LobeFloats;
    // Highest concentration a lobe gets (about 3 degrees wide).
    static constexpr float MaxKappa = 500.f;

    // Fits up to MaxLobes lobes to n photons (directions wi, unit; weights
    // w >= 0) by weighted spherical k-means (deterministic: the heaviest
    // photon seeds the first lobe, then the photon farthest from the lobes
    // by weight times 1 - cosine), then merges lobes that are one light
    // (together they spread less than twice the wider alone), writing
    // Floats statistics to out.
    static void fit(const Vec3* wi, const float* w, int n, float* out);
    // Adds n photons to the statistics in out, each to the lobe whose mean
    // direction is closest among `means` (Floats statistics whose lobes fix
    // the assignment; lobes without weight take nothing). If `means` has no
    // lobe, fits instead.
    static void assign(const float* means, const Vec3* wi, const float* w, int n, float* out);
    // Lobe `j` of the statistics as a vMF lobe (weight W, not normalised);
    // false if it holds no light.
    static bool lobe(const float* stats, int j, VmfLobe& out);
    // The running mean over photon batches (refineRadianceCache): W and S
    // become keep * stats + add * fresh, the counts N add up.
    static void average(float* stats, const float* fresh, float keep, float add);
    // The lobes of the statistics that hold light.
    static PreparedLobes prepare(const float* stats);
};
static_assert(DirectionLobes::MaxLobes == 4, "PreparedLobes holds four lobes");

}  // namespace vdbmarch
