// Google Benchmark kernels: the hot paths of the marchers.
//   build/bin/vdbmarch_kernels --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>

#include "cache/sh.h"
#include "core/rng.h"
#include "core/sampling.h"
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
    openvdb::initialize();
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

}  // namespace

BENCHMARK_MAIN();
