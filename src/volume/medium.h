// Participating media: a homogeneous box (or all space) and VDB density grids.
// The interface hides OpenVDB so that only src/volume/*.cpp include its heavy
// headers. Per-thread state (VDB accessors, DDA scratch) lives in a
// MediumQuery made once per work block of a render.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/blackbody.h"
#include "core/math.h"
#include "parse/scene_desc.h"

namespace vdbmarch {

// A piece of a ray with an upper bound on the density over it (per VDB
// block: times sigma_t it is the local majorant of delta and ratio tracking)
// and a lower bound (the control of residual ratio tracking; 0 where none is
// known). Densities, not coefficients.
struct DensityBound {
    float t0, t1, maxDensity;
    float minDensity = 0;
};

class MediumQuery {
public:
    virtual ~MediumQuery() = default;
    // Density (grid value x density_scale, sanitised >= 0) at a world point.
    virtual float density(const Vec3& p) = 0;
    // scale x emission grid value at a world point (0 without emission); with
    // blackbody emission the temperature in Kelvin.
    virtual float emission(const Vec3& p) = 0;
    // Appends the parametric intervals of ray r within [tMin, tMax] where the
    // density may be non-zero, in increasing order. Everything outside them is
    // empty space that the marchers skip.
    virtual void activeIntervals(const Ray& r, float tMin, float tMax, std::vector<Interval>& out) = 0;
    // Media of constant density integrate exactly: sets the integral of the
    // density over [tMin, tMax] and returns true. Gridded media return false
    // and are marched.
    virtual bool densityIntegral(const Ray& r, float tMin, float tMax, float& integral) { return false; }
    // Segments covering every point of [tMin, tMax] where the density may be
    // non-zero, each with an upper bound of the density on it (per 8^3 block
    // for VDB grids, constant for homogeneous media), produced lazily: visit
    // is called in increasing t until it returns false (a delta tracker
    // stops at its first real collision without walking the rest of the ray).
    virtual void forEachDensityBound(const Ray& r, float tMin, float tMax,
                                 const std::function<bool(const DensityBound&)>& visit) = 0;
};

// Picks points of an emissive medium for photon emission. The pdf (per unit
// world volume) is positive wherever the trilinear emission can be, so the
// emitted power estimate 4 pi sigma_a rho L_e / pdf is unbiased.
class EmissionSampler {
public:
    virtual ~EmissionSampler() = default;
    virtual void sample(const float u[4], Vec3& p, float& pdf) const = 0;
    // Approximate integral of density x emission value over the grid (world
    // volume units), used to share photons between lights.
    virtual float integralEstimate() const = 0;
    // Blackbody emission: the integral of density x blackbodyRadiance(T) per
    // channel instead (the value, a temperature, is not a radiance).
    virtual Color blackbodyIntegral() const { return Color(0); }
};

class Medium {
public:
    virtual ~Medium() = default;
    virtual std::unique_ptr<MediumQuery> makeQuery() const = 0;
    // World bounds of the region with density (infinite for unbounded fog).
    virtual BBox worldBounds() const = 0;
    // Smallest world-space voxel edge (0 for homogeneous media).
    virtual float minVoxelSize() const { return 0; }
    virtual float maxDensity() const = 0;
    virtual size_t activeVoxelCount() const { return 0; }
    // Bytes held for lookups and walks (the blocks, their index, an emission
    // grid); what predictMediumMemory's `resident` predicts.
    virtual uint64_t memoryBytes() const { return 0; }
    // World boxes that together cover every point with density > 0: one per
    // non-empty 8^3 VDB block, the box of a bounded homogeneous medium, none
    // for unbounded fog (which has an infinite worldBounds()).
    virtual void activeBoxes(std::vector<BBox>& out) const = 0;
    // Null when the medium does not emit.
    virtual std::unique_ptr<EmissionSampler> makeEmissionSampler() const { return nullptr; }
    // True when the medium can never attenuate or emit (skip it entirely).
    bool isVacuum() const {
        return maxDensity() <= 0 || (isBlack(sigma_a) && isBlack(sigma_s));
    }

    std::string name;
    Color sigma_a, sigma_s;  // per world unit, per unit density
    float g = 0;
    bool hasEmission = false;
    // L_e = emissionColor x emission(p); with blackbody emission
    // L_e = emissionColor x blackbodyRadiance(emission(p)), the colour being
    // the tint times the intensity.
    Color emissionColor{0, 0, 0};
    bool blackbody = false;

    // L_e for an emission value e > 0. The scalar product is the same
    // operation per channel as emissionColor[c] * e.
    Color emitted(float e) const { return blackbody ? emissionColor * blackbodyRadiance(e) : emissionColor * e; }
};

std::unique_ptr<Medium> makeHomogeneousMedium(const MediumDesc& desc);
// Loads the VDB file; throws InputError naming the file and grid on failure.
std::unique_ptr<Medium> loadVdbMedium(const MediumDesc& desc);

// Memory a medium takes, predicted from its VDB grids' metadata before any
// value is read (docs/memory.md: the formula and its measured accuracy); all
// zero for homogeneous media and files without the metadata.
struct MediumMemory {
    uint64_t gridBytes = 0;  // the density grid as OpenVDB holds it
    uint64_t loading = 0;    // peak while it loads, above what the process held
    uint64_t resident = 0;   // held afterwards, while rendering
};
MediumMemory predictMediumMemory(const MediumDesc& desc);

// Summary of a VDB grid, used to build a scene for a bare .vdb file.
struct VdbGridSummary {
    std::string gridName;
    BBox worldBounds;
    float voxelSize = 0;      // smallest world voxel edge
    size_t activeVoxels = 0;
    float minValue = 0, maxValue = 0, meanValue = 0;  // over active values
};
// Picks `grid`, or when empty the grid named "density", else the first float grid.
VdbGridSummary summarizeVdb(const std::string& file, const std::string& grid);

// Names and types of every grid in a file ("density (float)", ...).
std::vector<std::string> listVdbGrids(const std::string& file);

// Reads every grid of the file fully (any value type); returns the active
// voxels in all. Throws InputError naming the file and grid on failure.
size_t readEveryGrid(const std::string& file);

// openvdb::initialize(), once per process: the library calls it before it
// reads or writes VDB files, and so does any code that uses OpenVDB directly.
void initOpenVdb();

}  // namespace vdbmarch
