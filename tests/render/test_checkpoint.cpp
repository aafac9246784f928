// Checkpoints (render --checkpoint, docs/farm.md): a render stopped at a
// sample boundary and resumed from its saved state, through a checkpoint
// file, is bit-identical to the uninterrupted render for every method
// (photon passes, cache refinements and the cache included), with every AOV,
// cropped, and for a part by photon passes; the time a timed render already
// spent counts; and a checkpoint file that is damaged, truncated, or written
// for another version, scene, window or budget is refused with a message
// naming the file and what differs.
#include <cstring>
#include <functional>
#include <optional>

#include "illumination/illumination.h"
#include "render/checkpoint.h"
#include "support/support.h"

namespace vdbmarch::test {
namespace {

std::unique_ptr<Scene> smallScene(Method method, const std::vector<std::string>& extra = {}) {
    std::vector<std::string> o = {"camera.resolution=[24,16]", "render.spp=10", "render.max_depth=4",
                                  "photons.count=10000", "photons.spp_per_pass=2", "render.step=0.12",
                                  methodOverride(method)};
    o.insert(o.end(), extra.begin(), extra.end());
    return buildScene(loadSceneFile(samplePath("cloud.json"), o));
}

const CheckpointIdentity kIdentity{"v", "hash", "window", "budget"};

// Renders with a checkpoint handed to `save` at every sample boundary and a
// stop at the `at`-th.
void stopAt(const Scene& scene, RenderOptions options, int at,
            const std::function<void(const RenderCheckpoint&)>& save) {
    int boundaries = 0;
    CheckpointHooks hooks;
    hooks.everySeconds = 1e-9;  // save at every boundary (and take one sample per chunk)
    hooks.save = save;
    hooks.stopRequested = [&] { return ++boundaries >= at; };
    options.checkpoint = hooks;
    EXPECT_TRUE(renderImage(scene, options).interrupted);
}

// The same, the last state going through a file. Returns the state.
RenderCheckpoint interrupted(const Scene& scene, RenderOptions options, int at, const std::string& file) {
    stopAt(scene, options, at, [&](const RenderCheckpoint& c) { writeCheckpointFile(file, kIdentity, c); });
    return readCheckpointFile(file, kIdentity);
}

RenderResult resumed(const Scene& scene, RenderOptions options, const RenderCheckpoint& state) {
    CheckpointHooks hooks;
    hooks.everySeconds = 1e9;
    hooks.save = [](const RenderCheckpoint&) {};
    hooks.stopRequested = [] { return false; };
    hooks.resume = &state;
    options.checkpoint = hooks;
    return renderImage(scene, options);
}


void expectSameRender(const RenderResult& a, const RenderResult& b, const std::string& what) {
    EXPECT_FALSE(b.interrupted) << what;
    EXPECT_EQ(a.spp, b.spp) << what;
    EXPECT_TRUE(sameBits(a.image.rgba, b.image.rgba)) << what;
    ASSERT_EQ(a.layers.size(), b.layers.size()) << what;
    for (size_t i = 0; i < a.layers.size(); ++i)
        EXPECT_TRUE(sameBits(a.layers[i].pixels, b.layers[i].pixels)) << what << ": layer " << a.layers[i].name;
    ASSERT_EQ(a.passSums.size(), b.passSums.size()) << what;
    for (size_t i = 0; i < a.passSums.size(); ++i) {
        EXPECT_EQ(a.passSums[i].samples, b.passSums[i].samples) << what;
        EXPECT_EQ(0, std::memcmp(a.passSums[i].L.data(), b.passSums[i].L.data(), a.passSums[i].L.size() * sizeof(ColorSum)))
            << what << ": pass " << i;
    }
    EXPECT_EQ(a.counters.cameraRays, b.counters.cameraRays) << what;
}

// A render to a noise target: which pixels stopped is part of the state.
TEST(Checkpoint, NoiseTargetResumesBitIdentically) {
    TempDir dir("checkpoint_noise");
    const auto scene = smallScene(Method::Reference, {"render.noise=0.08", "render.spp=400"});
    const RenderResult whole = renderImage(*scene);
    ASSERT_TRUE(whole.reachedNoiseTarget);
    ASSERT_LT(whole.meanSpp, double(whole.spp));  // some pixels stopped early
    for (int stopAt : {3, whole.spp - 2}) {
        const RenderCheckpoint state = interrupted(*scene, {}, stopAt, dir / "noise.ckpt");
        expectSameRender(whole, resumed(*scene, {}, state), str("noise target, stopped at ", stopAt));
    }
}

class CheckpointMethods : public ::testing::TestWithParam<Method> {};

TEST_P(CheckpointMethods, ResumedRenderIsBitIdentical) {
    TempDir dir("checkpoint");
    // Every AOV; and a crop of the frame.
    for (bool aovsAndCrop : {false, true}) {
        const auto scene = smallScene(GetParam(), aovsAndCrop ? std::vector<std::string>{
                                                                    R"(render.aovs=["depth","albedo","normal","direct","indirect"])"}
                                                              : std::vector<std::string>{});
        RenderOptions options;
        if (aovsAndCrop) options.crop = PixelRect{3, 2, 19, 13};
        const RenderResult whole = renderImage(*scene, options);
        // Stops early (after 2 samples: inside the second photon pass) and
        // late (after 7: passes and cache refinements at 1 and 3 behind).
        for (int stopAt : {3, 8}) {
            const RenderCheckpoint state = interrupted(*scene, options, stopAt, dir / "ck");
            EXPECT_EQ(state.nextSample, stopAt - 1);
            expectSameRender(whole, resumed(*scene, options, state),
                             str(methodName(GetParam()), aovsAndCrop ? " with AOVs, cropped" : "", ", stopped at ",
                                 state.nextSample));
        }
    }
}

// A stop resumed in the same process (auto's pilot stages) takes over the
// photons and cache the render stopped with instead of tracing them again,
// and still renders the same bits; a file carries no photons.
TEST_P(CheckpointMethods, AResumeInMemoryTakesOverThePhotonsAndCache) {
    TempDir dir("checkpoint_memory");
    const auto scene = smallScene(GetParam());
    const RenderResult whole = renderImage(*scene);
    for (int at : {3, 8}) {
        std::optional<RenderCheckpoint> state;
        stopAt(*scene, {}, at, [&](const RenderCheckpoint& c) { state = c; });
        ASSERT_TRUE(state && state->illumination);
        const std::shared_ptr<Illumination> carried = state->illumination;
        expectSameRender(whole, resumed(*scene, {}, *state),
                         str(methodName(GetParam()), ", in memory, stopped at ", state->nextSample));
        // The resume advanced the very photons it was handed to the last pass.
        EXPECT_EQ(carried->photonPass, whole.photonPasses - 1);
        writeCheckpointFile(dir / "ck", kIdentity, *state);
        EXPECT_FALSE(readCheckpointFile(dir / "ck", kIdentity).illumination);
    }
}

INSTANTIATE_TEST_SUITE_P(Methods, CheckpointMethods, ::testing::ValuesIn(estimatorMethods()), methodParamName);

// The emitted part's halves (RenderOptions::keepEmitted, the denoiser's
// input) are part of the state, in the open pass and the folded sums.
TEST(Checkpoint, TheEmittedPartResumesBitIdentically) {
    TempDir dir("checkpoint_emitted");
    for (Method method : {Method::Guided, Method::Reference}) {
        const auto scene = buildScene(loadSceneFile(
            samplePath("plume.json"), {"camera.resolution=[24,16]", "render.spp=10", "photons.count=10000",
                                       "photons.spp_per_pass=2", "render.step=0.12", methodOverride(method)}));
        RenderOptions options;
        options.keepHalves = options.keepEmitted = true;
        const RenderResult whole = renderImage(*scene, options);
        ASSERT_FALSE(whole.emittedEven.empty());
        for (int stopAt : {3, 8}) {
            const RenderCheckpoint state = interrupted(*scene, options, stopAt, dir / "ck");
            const RenderResult r = resumed(*scene, options, state);
            const std::string what = str(methodName(method), ", stopped at ", state.nextSample);
            expectSameRender(whole, r, what);
            EXPECT_TRUE(sameBits(whole.emittedEven.rgba, r.emittedEven.rgba)) << what;
            EXPECT_TRUE(sameBits(whole.emittedOdd.rgba, r.emittedOdd.rgba)) << what;
            EXPECT_TRUE(sameBits(whole.evenHalf.rgba, r.evenHalf.rgba)) << what;
        }
    }
}

TEST(Checkpoint, APartByPhotonPassesResumesBitIdentical) {
    TempDir dir("checkpoint");
    const auto scene = smallScene(Method::Guided);
    RenderOptions options;
    options.photonPassRange = std::make_pair(1, 4);  // samples 2-7
    const RenderResult whole = renderImage(*scene, options);
    ASSERT_EQ(whole.passSums.size(), 3u);
    const RenderCheckpoint state = interrupted(*scene, options, 4, dir / "ck");  // samples 2-4 done
    EXPECT_EQ(state.nextSample, 5);
    EXPECT_EQ(state.passSums.size(), 1u);
    expectSameRender(whole, resumed(*scene, options, state), "passes 1-4");
}

TEST(Checkpoint, TheTimeAlreadySpentCounts) {
    TempDir dir("checkpoint");
    const auto scene = smallScene(Method::Reference);
    RenderOptions options;
    options.timeBudget = 30;
    RenderCheckpoint state = interrupted(*scene, options, 4, dir / "ck");
    ASSERT_EQ(state.nextSample, 3);
    // A checkpoint that says the budget is spent: one more pass (a render
    // always takes at least one), then the render ends.
    state.seconds = 31;
    const RenderResult r = resumed(*scene, options, state);
    EXPECT_EQ(r.spp, 4);
    EXPECT_GE(r.seconds, 31.0);
}

TEST(Checkpoint, DamagedTruncatedOrForeignFilesAreRefused) {
    TempDir dir("checkpoint");
    const auto scene = smallScene(Method::Reference);
    const std::string file = dir / "ck";
    interrupted(*scene, {}, 3, file);
    const std::string bytes = readBytes(file);
    ASSERT_GT(bytes.size(), 1000u);

    auto refused = [&](const std::string& contents, const CheckpointIdentity& id, std::initializer_list<std::string> needles) {
        const std::string path = dir.write("bad", contents);
        std::vector<std::string> all = {path};
        all.insert(all.end(), needles.begin(), needles.end());
        const std::string msg = errorOf<InputError>([&] { readCheckpointFile(path, id); });
        for (const std::string& n : all) EXPECT_CONTAINS(msg, n);
    };
    CheckpointIdentity other = kIdentity;
    other.version = "0.1.0";
    refused(bytes, other, {"another vdbmarch version", "v;", "0.1.0"});
    other = kIdentity;
    other.renderHash = "abc";
    refused(bytes, other, {"another scene or other settings", "hash", "abc"});
    other = kIdentity;
    other.window = "0,0,8,8";
    refused(bytes, other, {"other pixels", "0,0,8,8"});
    other = kIdentity;
    other.budget = "spp 11";
    refused(bytes, other, {"another sample budget", "spp 11"});
    refused(bytes.substr(0, bytes.size() - 100), kIdentity, {"damaged or truncated"});
    refused(bytes.substr(0, 30), kIdentity, {"damaged or truncated"});
    std::string flipped = bytes;
    flipped[bytes.size() / 2] = char(flipped[bytes.size() / 2] ^ 0x10);
    refused(flipped, kIdentity, {"damaged or truncated"});
    refused("P6\n2 2\n255\n", kIdentity, {"not a vdbmarch checkpoint"});
    refused("vdbmarch checkpoint 9\n{}\n", kIdentity, {"another format"});
    expectErrorContaining<InputError>([&] { readCheckpointFile(dir / "missing", kIdentity); },
                                      {dir / "missing", "cannot read"});
    // The intact file still reads.
    EXPECT_EQ(readCheckpointFile(file, kIdentity).nextSample, 2);
}

}  // namespace
}  // namespace vdbmarch::test
