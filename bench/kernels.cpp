// Google Benchmark kernels: the hot paths of the marchers.
//   build/bin/vdbmarch_kernels --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>

#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "cache/sh.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "denoise/denoise.h"
#include "estimators/estimator.h"
#include "estimators/segment_marcher.h"
#include "illumination/illumination.h"
#include "parse/scene_desc.h"
#include "scene/scene.h"
#include "transport/media_point.h"
#include "transport/phase.h"
#include "transport/roulette.h"
#include "volume/medium.h"

using namespace vdbmarch;

namespace {

const std::string kCloud = std::string(VDBMARCH_SOURCE_DIR) + "/vdb_samples/cloud.vdb";

MediumDesc cloudDesc() {
    MediumDesc d;
    d.type = MediumDesc::Type::Vdb;
    d.file = kCloud;
    d.sigma_s = Vec3(1);
    return d;
}

// Points along short coherent walks (like march samples), inside the cloud's bbox.
std::vector<Vec3> walkPoints(size_t n, float step) {
    Rng rng(7);
    std::vector<Vec3> pts;
    Vec3 p, d;
    for (size_t i = 0; i < n; ++i) {
        if (i % 64 == 0) {
            p = Vec3(-0.9f + 1.8f * rng.uniform(), -0.4f + 1.1f * rng.uniform(), -0.6f + 1.2f * rng.uniform());
            d = sampleUniformSphere(rng.uniform(), rng.uniform());
        }
        pts.push_back(p);
        p += d * step;
    }
    return pts;
}

void BM_DensityPaddedBlocks(benchmark::State& state) {
    auto medium = loadVdbMedium(cloudDesc());
    auto q = medium->makeQuery();
    auto pts = walkPoints(1 << 16, 0.016f);
    size_t i = 0;
    for (auto _ : state) {
        benchmark::DoNotOptimize(q->density(pts[i]));
        i = (i + 1) & (pts.size() - 1);
    }
    state.SetItemsProcessed(int64_t(state.iterations()));
}
BENCHMARK(BM_DensityPaddedBlocks);

// OpenVDB's own trilinear sampler on the same points, for comparison.
void BM_DensityOpenVdbBoxSampler(benchmark::State& state) {
    initOpenVdb();
    openvdb::io::File f(kCloud);
    f.open();
    auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(f.readGrid("density"));
    auto acc = grid->getConstAccessor();
    openvdb::tools::GridSampler<openvdb::FloatGrid::ConstAccessor, openvdb::tools::BoxSampler> sampler(
        acc, grid->transform());
    auto pts = walkPoints(1 << 16, 0.016f);
    size_t i = 0;
    for (auto _ : state) {
        const Vec3& p = pts[i];
        benchmark::DoNotOptimize(sampler.wsSample(openvdb::Vec3d(p.x, p.y, p.z)));
        i = (i + 1) & (pts.size() - 1);
    }
    state.SetItemsProcessed(int64_t(state.iterations()));
}
BENCHMARK(BM_DensityOpenVdbBoxSampler);

void BM_ActiveIntervals(benchmark::State& state) {
    auto medium = loadVdbMedium(cloudDesc());
    auto q = medium->makeQuery();
    Rng rng(3);
    std::vector<Ray> rays;
    for (int i = 0; i < 4096; ++i) {
        Vec3 d = sampleUniformSphere(rng.uniform(), rng.uniform());
        rays.push_back({Vec3(0, 0.17f, 0) - d * 3.f, d});
    }
    std::vector<Interval> out;
    size_t i = 0;
    for (auto _ : state) {
        out.clear();
        q->activeIntervals(rays[i], 0, Infinity, out);
        benchmark::DoNotOptimize(out.data());
        i = (i + 1) & 4095;
    }
    state.SetItemsProcessed(int64_t(state.iterations()));
}
BENCHMARK(BM_ActiveIntervals);

void BM_HenyeyGreensteinSample(benchmark::State& state) {
    Rng rng(1);
    for (auto _ : state) {
        float c = sampleHgCosTheta(rng.uniform(), 0.8f);
        benchmark::DoNotOptimize(directionAround(Vec3(0, 0, 1), c, rng.uniform()));
    }
}
BENCHMARK(BM_HenyeyGreensteinSample);

// Real SH basis per direction (once per camera ray, once per photon per
// cache cell): order 3 is the expanded polynomial path, order 8 the recurrence.
void BM_EvalSh(benchmark::State& state) {
    const int order = int(state.range(0));
    Rng rng(5);
    std::vector<Vec3> dirs;
    for (int i = 0; i < 4096; ++i) dirs.push_back(sampleUniformSphere(rng.uniform(), rng.uniform()));
    float Y[shCount(MaxShOrder)];
    size_t i = 0;
    for (auto _ : state) {
        evalSh(order, dirs[i], Y);
        benchmark::DoNotOptimize(Y);
        benchmark::ClobberMemory();
        i = (i + 1) & 4095;
    }
    state.SetItemsProcessed(int64_t(state.iterations()));
}
BENCHMARK(BM_EvalSh)->Arg(3)->Arg(8);

// Sampling a continuation direction: PhaseMixture::sample around the ray
// (256 ray directions, g = 0.6).
void BM_PhaseMixtureSample(benchmark::State& state) {
    struct {
        std::vector<Vec3> rays;
        PhaseMixture phase;
    } in;
    Rng rng(9);
    in.phase.add(Color(1), 0.6f);
    for (int i = 0; i < 256; ++i) in.rays.push_back(sampleUniformSphere(rng.uniform(), rng.uniform()));
    size_t i = 0;
    for (auto _ : state) {
        Color w(1);
        float pdf;
        benchmark::DoNotOptimize(in.phase.sample(in.rays[i], rng.uniform(), rng.uniform(), rng.uniform(), w, pdf));
        benchmark::DoNotOptimize(w);
        i = (i + 1) & 255;
    }
    state.SetItemsProcessed(int64_t(state.iterations()));
}
BENCHMARK(BM_PhaseMixtureSample);

// ---------------------------------------------------------------------------
// Issue 5: the cost of one march sample against one trilinear density lookup
// on the same grid (target: at most 3x).
//
//   vdbmarch_kernels --benchmark_filter='Trilinear|MarchSample'
//       --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// Scene (built in code through the scene parser): vdb_samples/cloud.vdb with
// sigma_a 0.3, sigma_s 5, g 0.8, the sample's directional light and camera,
// black background (so L_i is one shadow ray to the light, no environment
// ray), render.max_depth 1 (single scattering: no photon map for L_i), the
// automatic step (one voxel, 0.016). Camera rays: pixel centres of a 64x48
// grid over the 640x480 frame, keeping the rays whose empty-space intervals
// are not empty (rays that miss every active block do no marching). Every
// iteration traces the same rays with the same random streams, so every
// iteration does the same work.
//
// Benchmarks: BM_TrilinearDensityLookup (one MediumQuery::density, the
// baseline of the ratio), BM_TrilinearDensityLookupLatency (the same, made
// serial), BM_TrilinearEvalMedia (lookup + the step's coefficients),
// BM_GuidedMarchSample/* and BM_TransmittanceMarchSample/* (time per march
// sample, variants below). Ratio = time_per_march_sample / lookup time.

struct MarchBench {
    std::unique_ptr<Scene> scene;
    std::vector<Ray> rays;
};

// absorbing: sigma_a 5.3, sigma_s 0 (the same extinction, so the same walk,
// but nothing scatters: no histogram, no L_i).
std::unique_ptr<Scene> benchScene(const std::string& method, const std::string& li, int raySamples, bool absorbing) {
    const std::string coefficients = absorbing ? R"("sigma_a": 5.3, "sigma_s": 0.0)" : R"("sigma_a": 0.3, "sigma_s": 5.0)";
    const std::string json = R"({
  "camera": { "position": [1.47, 0.88, 3.25], "look_at": [0.0, 0.17, 0.0], "fov_deg": 35,
              "resolution": [640, 480] },
  "lights": [ { "type": "directional", "direction": [0.55, -0.75, -0.35], "irradiance": [6.4, 6.0, 5.4] } ],
  "media": [ { "name": "cloud", "type": "vdb", "file": "cloud.vdb",
               )" + coefficients + R"(, "g": 0.8 } ],
  "background": 0,
  "render": { "method": ")" + method + R"(", "max_depth": 1, "seed": 1, "li": ")" + li +
                             R"(", "ray_samples": )" + std::to_string(raySamples) + R"( }
})";
    // The file name only places relative paths (cloud.vdb) and names errors.
    return buildScene(parseSceneText(json, std::string(VDBMARCH_SOURCE_DIR) + "/vdb_samples/kernels_bench.json"));
}

// Camera rays through the cloud (see above); the same for every variant.
std::vector<Ray> benchRays(const Scene& scene) {
    ThreadContext ctx(scene);
    std::vector<Ray> rays;
    const int gw = 64, gh = 48, w = scene.camera->width(), h = scene.camera->height();
    for (int j = 0; j < gh; ++j)
        for (int i = 0; i < gw; ++i) {
            Ray r = scene.camera->generateRay((float(i) + 0.5f) * float(w) / gw, (float(j) + 0.5f) * float(h) / gh);
            regionIntervals(ctx, Scene::WorldRegion, r, 0.f, Infinity, ctx.intervals);
            if (!ctx.intervals.empty()) rays.push_back(r);
        }
    return rays;
}

uint64_t raySeed(size_t i) { return hashValues(0x6b65726e656c, uint64_t(i)); }

// One scene per (li, ray_samples, absorbing), loaded once per process.
MarchBench& marchBench(const std::string& li, int raySamples, bool absorbing = false) {
    static std::map<std::string, std::unique_ptr<MarchBench>> all;
    auto& b = all[li + "/" + std::to_string(raySamples) + (absorbing ? "/absorbing" : "")];
    if (!b) {
        b = std::make_unique<MarchBench>();
        b->scene = benchScene("guided", li, raySamples, absorbing);
        b->rays = benchRays(*b->scene);
    }
    return *b;
}

// The points where the sampled marchers look the density up along those
// rays, in marching order: steps [k dx, (k + 1) dx) clipped to the active
// intervals, one point per step at the ray's jittered offset (the first
// uniform of the ray's stream, as in SampledMarcher::marchSegment), until the
// transmittance drops below the roulette threshold (where the marcher plays
// Russian roulette; the few survivors are not followed here).
const std::vector<Vec3>& marchPoints() {
    static const std::vector<Vec3> pts = [] {
        MarchBench& b = marchBench("photons", 4);
        const Scene& scene = *b.scene;
        ThreadContext ctx(scene);
        const Medium& m = *scene.media[0];
        const float sigmaT = maxComponent(m.sigma_a + m.sigma_s);
        const double dx = double(scene.step);
        std::vector<Vec3> out;
        for (size_t i = 0; i < b.rays.size(); ++i) {
            const Ray& ray = b.rays[i];
            Rng rng(raySeed(i));
            const double u = double(rng.uniform());
            regionIntervals(ctx, Scene::WorldRegion, ray, 0.f, Infinity, ctx.intervals);
            float T = 1;
            for (const Interval& iv : ctx.intervals) {
                for (double k = std::floor(double(iv.t0) / dx); T >= RouletteThreshold; k += 1) {
                    const double a = std::max(double(iv.t0), k * dx), b1 = std::min(double(iv.t1), (k + 1) * dx);
                    if (a >= double(iv.t1)) break;
                    if (!(b1 > a)) continue;
                    const Vec3 x = ray.at(float(a + u * (b1 - a)));
                    out.push_back(x);
                    T *= std::exp(-sigmaT * ctx.queries[0]->density(x) * float(b1 - a));
                }
                if (T < RouletteThreshold) break;
            }
        }
        return out;
    }();
    return pts;
}

// One trilinear density lookup (MediumQuery::density: the padded-block
// sampler with its per-thread block cache) at the march points above, in
// order: the access pattern of marching, timed without anything else.
void BM_TrilinearDensityLookup(benchmark::State& state) {
    MarchBench& b = marchBench("photons", 4);
    const auto& pts = marchPoints();
    auto q = b.scene->media[0]->makeQuery();
    size_t i = 0;
    for (auto _ : state) {
        benchmark::DoNotOptimize(q->density(pts[i]));
        if (++i == pts.size()) i = 0;
    }
    state.SetItemsProcessed(int64_t(state.iterations()));
    state.counters["points"] = double(pts.size());
}
BENCHMARK(BM_TrilinearDensityLookup);

// The same lookups made serial: the next point's index depends on the last
// result (the added term is always 0), so consecutive lookups cannot overlap
// in the out-of-order core. This is the latency of one lookup, the figure a
// march step sees when the rest of the step (exponentials, histogram, branches
// on the density) fills the reorder window between two lookups; the plain
// benchmark above is the throughput of back-to-back independent lookups.
void BM_TrilinearDensityLookupLatency(benchmark::State& state) {
    MarchBench& b = marchBench("photons", 4);
    const auto& pts = marchPoints();
    auto q = b.scene->media[0]->makeQuery();
    size_t i = 0;
    for (auto _ : state) {
        const float d = q->density(pts[i]);
        i += 1 + size_t(d < 0);  // density is >= 0: always + 1, but only known after the lookup
        if (i >= pts.size()) i = 0;
    }
    state.SetItemsProcessed(int64_t(state.iterations()));
}
BENCHMARK(BM_TrilinearDensityLookupLatency);

// evalMedia at the same points: the lookup plus the per-step coefficients
// (sigma_a, sigma_s, sigma_t colours, phase-mixture entry) every marcher
// computes from it. Part of a march sample, shown to split its cost.
void BM_TrilinearEvalMedia(benchmark::State& state) {
    MarchBench& b = marchBench("photons", 4);
    const auto& pts = marchPoints();
    ThreadContext ctx(*b.scene);
    MediumPoint mp;
    size_t i = 0;
    for (auto _ : state) {
        evalMedia(ctx, Scene::WorldRegion, pts[i], mp);
        benchmark::DoNotOptimize(mp);
        if (++i == pts.size()) i = 0;
    }
    state.SetItemsProcessed(int64_t(state.iterations()));
}
BENCHMARK(BM_TrilinearEvalMedia);

// Time per march sample of a sampled marcher: one iteration is
// marcher->radiance() over every bench ray; the CPU time is divided by
// ThreadContext.counters.marchSamples (one per step of the per-ray walk), so
// a march sample's cost here includes everything amortised over the walk:
// active intervals, the histogram and its CDF (RayPdf), for guided the cache
// lookups h(t), and the L_i estimates at the positions drawn from the pdf.
// Counters (per camera ray): march_samples, li_samples (points where L_i was
// estimated), shadow_samples (medium samples along shadow rays).
//   li_photons_rs4: render.li "photons", ray_samples 4 (the default): L_i =
//                   one shadow ray to the directional light per L_i sample
//                   (max_depth 1: no photon map). The full cost.
//   li_photons_rs1: the same with ray_samples 1: fewer shadow rays per walk.
//   li_cache_rs4:   render.li "cache": L_i is one radiance-cache lookup, so
//                   the time is (almost) the pure walk + histogram + sampling.
//   walk_only:      (transmittance) the medium made purely absorbing with the
//                   same extinction (sigma_a 5.3, sigma_s 0): the same steps,
//                   but no histogram, pdf or L_i. The bare walk: intervals,
//                   evalMedia, the step's exponentials, roulette.
// Guided falls back to transmittance sampling without a cache; it always has
// one here (the Illumination is prepared for "guided"). Guided takes about 3x
// ray_samples L_i samples per bench ray: eq. 17 allots them relative to the
// mean over the whole image, whose rays mostly miss the cloud, and every
// bench ray crosses it.
void marchSampleBench(benchmark::State& state, const std::string& method, const std::string& li, int raySamples,
                      bool absorbing = false) {
    MarchBench& b = marchBench(li, raySamples, absorbing);
    // Photons, cache and (guided) the eq. 17 pre-pass, once per process.
    static std::map<std::string, std::unique_ptr<Estimator>> marchers;
    auto& marcher = marchers[method + "/" + li + "/" + std::to_string(raySamples) + (absorbing ? "/absorbing" : "")];
    if (!marcher) {
        Method m = Method::Uniform;
        parseMethod(method, m);
        marcher = makeEstimator(m, *b.scene, std::make_shared<Illumination>(prepareIllumination(*b.scene, m)));
    }
    ThreadContext ctx(*b.scene);
    for (auto _ : state) {
        for (size_t i = 0; i < b.rays.size(); ++i) {
            Rng rng(raySeed(i));
            benchmark::DoNotOptimize(marcher->radiance(b.rays[i], rng, ctx));
        }
    }
    const RenderCounters& c = ctx.counters;
    const double rays = double(c.cameraRays);
    state.SetItemsProcessed(int64_t(c.marchSamples));
    state.counters["time_per_march_sample"] =
        benchmark::Counter(double(c.marchSamples), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
    state.counters["march_samples_per_ray"] = double(c.marchSamples) / rays;
    state.counters["li_samples_per_ray"] = double(c.liSamples) / rays;
    state.counters["shadow_samples_per_ray"] = double(c.shadowSamples) / rays;
    state.counters["rays"] = double(b.rays.size());
}

void BM_GuidedMarchSample(benchmark::State& state, const char* li, int raySamples) {
    marchSampleBench(state, "guided", li, raySamples);
}
void BM_TransmittanceMarchSample(benchmark::State& state, const char* li, int raySamples, bool absorbing = false) {
    marchSampleBench(state, "transmittance", li, raySamples, absorbing);
}
BENCHMARK_CAPTURE(BM_GuidedMarchSample, li_photons_rs4, "photons", 4)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_GuidedMarchSample, li_photons_rs1, "photons", 1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_GuidedMarchSample, li_cache_rs4, "cache", 4)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_TransmittanceMarchSample, li_photons_rs4, "photons", 4)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_TransmittanceMarchSample, li_photons_rs1, "photons", 1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_TransmittanceMarchSample, li_cache_rs4, "cache", 4)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_TransmittanceMarchSample, walk_only, "photons", 4, true)->Unit(benchmark::kMillisecond);

// Denoising a 640x480 frame (src/denoise/): two noisy half renders (a soft
// gradient with discs of sharp edges, Gaussian noise of sigma 0.15 per half),
// alpha and the three features (albedo, normal, depth) with noise of their
// own. The argument is the thread count; real time, since the work is
// spread over a task arena.
const DenoiseInput& denoiseBenchInput() {
    static const DenoiseInput input = [] {
        DenoiseInput in;
        in.width = 640;
        in.height = 480;
        Rng rng(11);
        auto gaussian = [&] {
            const float u1 = 1.f - rng.uniform(), u2 = rng.uniform();
            return std::sqrt(-2.f * std::log(u1)) * std::cos(2.f * Pi * u2);
        };
        auto noise = [&](float sigma) { return sigma * Vec3(gaussian(), gaussian(), gaussian()); };
        for (int y = 0; y < in.height; ++y)
            for (int x = 0; x < in.width; ++x) {
                const float u = x / 640.f, v = y / 480.f;
                const bool disc = std::hypot(x - 200.f, y - 240.f) < 120.f || std::hypot(x - 470.f, y - 200.f) < 80.f;
                const Color c = disc ? Color(0.9f - 0.2f * u, 0.7f, 0.4f + 0.2f * v)
                                     : Color(0.2f + 0.3f * u, 0.25f + 0.2f * v, 0.3f + 0.1f * (u + v));
                const float alpha = disc ? 1.f : 0.5f + 0.3f * u;
                in.halfA.push_back(c + noise(0.15f));
                in.halfB.push_back(c + noise(0.15f));
                in.alphaA.push_back(alpha + 0.1f * gaussian());
                in.alphaB.push_back(alpha + 0.1f * gaussian());
                in.albedo.push_back((disc ? Color(0.8f, 0.6f, 0.5f) : Color(0.3f)) + noise(0.05f));
                in.normal.push_back((disc ? Vec3(0, 0, 1) : Vec3(0, 1, 0)) + noise(0.1f));
                in.depth.push_back((disc ? 5.f : 12.f) + 0.2f * gaussian());
            }
        return in;
    }();
    return input;
}

void BM_Denoise640x480(benchmark::State& state) {
    const DenoiseInput& in = denoiseBenchInput();
    DenoiseOptions options;
    options.threads = int(state.range(0));
    for (auto _ : state) benchmark::DoNotOptimize(denoise(in, options));
    state.SetItemsProcessed(int64_t(state.iterations()) * in.width * in.height);
}
BENCHMARK(BM_Denoise640x480)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
