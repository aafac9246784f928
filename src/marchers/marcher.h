// One interface for every way of estimating the radiance along a camera ray,
// and one factory table. Per-thread state lives in a ThreadContext.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/math.h"
#include "core/rng.h"
#include "parse/method.h"
#include "transport/thread_context.h"

namespace vdbmarch {

class Scene;
struct Illumination;

struct PathResult {
    Color L;              // radiance towards the camera
    float transmittance;  // fraction of the background seen (alpha = 1 - this)
    // The part of L after at most one scattering event (emission and
    // unscattered light included): filled only when render.aovs asks for
    // "direct" or "indirect" (docs/aovs.md), else zero.
    Color direct{0};
};

class Marcher {
public:
    virtual ~Marcher() = default;
    virtual PathResult radiance(const Ray& cameraRay, Rng& rng, ThreadContext& ctx) const = 0;
};

// Methods the factory table implements, in the order `--method` lists them
// (every Method: a test checks it). Method-parameterised tests run over it.
std::vector<Method> marcherMethods();
// The marchers estimate L_i from `illumination` (photon map, cache); when
// null it is prepared here from the scene (prepareIllumination).
std::unique_ptr<Marcher> makeMarcher(Method method, const Scene& scene,
                                     std::shared_ptr<const Illumination> illumination = nullptr);

// Constructors behind the factory table.
std::unique_ptr<Marcher> makeUniformMarcher(const Scene& scene, std::shared_ptr<const Illumination> il);
std::unique_ptr<Marcher> makeTransmittanceMarcher(const Scene& scene, std::shared_ptr<const Illumination> il);
std::unique_ptr<Marcher> makeGuidedMarcher(const Scene& scene, std::shared_ptr<const Illumination> il);
std::unique_ptr<Marcher> makeReferenceTracer(const Scene& scene, std::shared_ptr<const Illumination> il);
std::unique_ptr<Marcher> makeGuidedPathTracer(const Scene& scene, std::shared_ptr<const Illumination> il);

}  // namespace vdbmarch
