// One interface for every way of estimating the radiance along a camera ray,
// and one factory table. Per-thread state lives in a ThreadContext.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/math.h"
#include "core/rng.h"
#include "marchers/march_common.h"

namespace vdbmarch {

class Scene;
struct Illumination;

struct PathResult {
    Color L;              // radiance towards the camera
    float transmittance;  // fraction of the background seen (alpha = 1 - this)
};

class Marcher {
public:
    virtual ~Marcher() = default;
    virtual PathResult radiance(const Ray& cameraRay, Rng& rng, ThreadContext& ctx) const = 0;
};

// Methods this build implements, in the order `--method` lists them.
std::vector<std::string> marcherNames();
// Throws InputError for an unknown name, listing the known ones. The
// marchers estimate L_i from `illumination` (photon map, cache); when null it
// is prepared here from the scene (prepareIllumination).
std::unique_ptr<Marcher> makeMarcher(const std::string& method, const Scene& scene,
                                     std::shared_ptr<const Illumination> illumination = nullptr);

// Constructors behind the factory table.
std::unique_ptr<Marcher> makeUniformMarcher(const Scene& scene, std::shared_ptr<const Illumination> il);
std::unique_ptr<Marcher> makeTransmittanceMarcher(const Scene& scene, std::shared_ptr<const Illumination> il);
std::unique_ptr<Marcher> makeGuidedMarcher(const Scene& scene, std::shared_ptr<const Illumination> il);
std::unique_ptr<Marcher> makeReferenceTracer(const Scene& scene, std::shared_ptr<const Illumination> il);

}  // namespace vdbmarch
