// Directions towards the beams of spot lights and collimated quads, mixed
// with f's own sampling at the path tracer's medium and diffuse vertices and
// at the marchers' L_i samples (experiments.beam_directions).
//
// In a thin haze lit by beams, most of the light a path can still find is
// in the beams (and on the floor patches they light); a phase- or
// cosine-sampled direction crosses one rarely, and the
// distance samples towards the light (light_distances.h) only pay on the
// segments that do. So with probability BeamShare a vertex draws a point
// in a beam instead and goes towards it: along the beam's axis over the
// axial range of the region's scattering media, in proportion to what each
// part of the axis scatters towards the vertex (the beam's power per unit
// length, about constant: for a spot the falloff 1/s^2 and the disc's area
// s^2 cancel, a collimated beam has neither; times the phase towards the
// vertex over the squared distance; piecewise constant on bins), and
// uniform over the cross-section there (a spot's disc, the quad seen along
// a collimated beam). The density of that direction is the volume density
// integrated along the ray (times t^2), in closed form per bin
// (beamDirectionPdf). The vertex weighs by the
// one-sample mixture, f / ((1 - p) p_phase + p p_beams), so the estimate
// is unbiased for any beams and lights, and next-event estimation meets the
// same density by MIS (ScatterVertex::pathPdf).
#pragma once

#include <map>
#include <vector>

#include "core/math.h"
#include "core/rng.h"
#include "strategies/strategy.h"

namespace vdbmarch {

class LightDistances;
class BeamDirections;

// The share of the beams in the mixture.
constexpr float BeamShare = 0.3f;

// A vertex's direction sampler: f's own sampling (the phase function, or
// the cosine on a diffuse surface) mixed with the beams of its region.
struct BeamMixture {
    BeamMixture() = default;
    BeamMixture(ThreadContext* c, const BeamDirections* b, int r, const ScatterVertex* v)
        : ctx(c), beams(b), region(r), vertex(v) {}
    ThreadContext* ctx = nullptr;
    const BeamDirections* beams = nullptr;
    int region = 0;
    const ScatterVertex* vertex = nullptr;

    // wi, f / pdf per channel (f cos on a surface) and the mixture's pdf;
    // pdf 0 (weight 0): no direction.
    Vec3 sample(Rng& rng, Color& weight, float& pdf) const;
    float pdf(const Vec3& wi) const;
    // The sum of the beams' weights as the vertex sees them (0: f alone).
    double beamWeight() const;

    // How the vertex sees each of the first MaxSights beams (its axial
    // position, distance from the axis, the phase's angle integral at the
    // beam's ends, and the beam's weight), computed once per vertex.
    struct Sight {
        double sx = 0, h = 1, g0 = 0, g1 = 0, weight = 0;
        // The angle integral at the axial bins' edges, made as they are
        // first asked for (bit i of `known`): a vertex's sampling and its
        // pdfs (next-event MIS, the sampled direction) ask for the same ones.
        static constexpr int Edges = 17;
        double edgeIntegral[Edges];
        unsigned known = 0;
    };
    static constexpr int MaxSights = 4;
    mutable Sight mSights[MaxSights];
    mutable double mBeamWeight = -1;  // beamWeight(); < 0 until the sights are made
    // For ScatterVertex::pathPdf.
    static float pdfOf(const void* self, const Vec3& wi) { return static_cast<const BeamMixture*>(self)->pdf(wi); }
};

// The beams of spot lights (cones) and collimated quads (prisms) that each
// region's medium vertices draw directions towards, built once per render.
// A region has them with experiments.beam_directions, a spot light whose
// distance sampling may pay there (light_distances.h) or a collimated quad
// that no blocking surface separates from it, and bounded, thin scattering
// media (an optical depth of at most 4 across their bounds at the densest
// extinction).
class BeamDirections final : public DirectionStrategy {
public:
    BeamDirections(const Scene& scene, const LightDistances& distances, size_t slot);

    struct Beam {
        int light;
        Vec3 apex, axis, e1, e2;  // a prism's "apex" is its quad's centre
        float tanCone = 0;
        float s0, s1;     // the axial range sampled (the region's media)
        float power = 1;  // scattered power per unit length of beam
        // A collimated quad's prism: the quad's edges u, v and their axial
        // parts, the dual vectors that give a point's quad coordinates
        // (|a|, |b| <= 1/2 inside) along the beam, and the cross-section's
        // area perpendicular to the axis.
        bool prism = false;
        Vec3 u, v, dualA, dualB;
        float uAxial = 0, vAxial = 0, area = 0;
    };
    struct Region {
        std::vector<Beam> beams;
        // The integral of the media's phase function over the scattering
        // angle, G(theta) = int_0^theta p(cos a) da, at BeamAngleSteps + 1
        // angles over [0, pi] (shared by the regions of one g).
        const std::vector<float>* angleIntegral = nullptr;
    };
    const Region& region(int r) const { return mRegions[size_t(r)]; }
    bool hasBeams(int r, bool skipPointLights) const { return !skipPointLights && !mRegions[size_t(r)].beams.empty(); }

    bool attach(ThreadContext& ctx, int region, ScatterVertex& v, bool skipPointLights) const override;
    Vec3 sample(ThreadContext& ctx, Rng& rng, Color& weight, float& pdf) const override;

    // The density (solid angle) of a direction drawn towards the region's
    // beams from x (no phase share).
    float beamDirectionPdf(ThreadContext& ctx, int region, const Vec3& x, const Vec3& wi) const;

private:
    struct Scratch final : ThreadContextExtension {
        BeamMixture mixture;  // the attached vertex's
    };
    std::vector<Region> mRegions;
    std::map<float, std::vector<float>> mAngleIntegrals;  // per g
    const size_t mSlot;
};

}  // namespace vdbmarch
