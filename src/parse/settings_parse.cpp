// The scene's settings objects from JSON: how to render, the A/B switches,
// photons and the radiance cache. Reads fields only.
#include "parse/settings_parse.h"

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "core/error.h"
#include "parse/method.h"

namespace vdbmarch {

namespace {

// render.aovs: an array of names, or one string of comma-separated names
// (what `--aovs depth,albedo` becomes).
AovSet parseAovs(const JsonReader& r) {
    const Json& v = r.raw("aovs");
    std::vector<std::string> names;
    if (v.is_string()) {
        std::string item;
        for (char c : v.get<std::string>() + ",") {
            if (c != ',') {
                if (c != ' ') item += c;
            } else if (!item.empty()) {
                names.push_back(item);
                item.clear();
            }
        }
    } else if (v.is_array()) {
        for (const Json& e : v) {
            if (!e.is_string()) r.fail("aovs", str("must list names as strings, got ", jsonExcerpt(e)));
            names.push_back(e.get<std::string>());
        }
    } else {
        r.fail("aovs", str("must be an array of names (or a comma-separated string), got ", jsonExcerpt(v)));
    }
    std::string allowed;
    for (const std::string& n : aovNames()) allowed += (allowed.empty() ? "" : ", ") + n;
    AovSet s;
    bool* flags[] = {&s.depth, &s.albedo, &s.normal, &s.direct, &s.indirect};  // aovNames() order
    for (const std::string& n : names) {
        const auto it = std::find(aovNames().begin(), aovNames().end(), n);
        if (it == aovNames().end())
            r.fail("aovs", str("unknown AOV \"", n, "\" (allowed: ", allowed, ")"));
        bool& flag = *flags[it - aovNames().begin()];
        if (flag) r.fail("aovs", str("lists \"", n, "\" twice"));
        flag = true;
    }
    return s;
}

}  // namespace

const std::vector<std::string>& aovNames() {
    static const std::vector<std::string> names = {"depth", "albedo", "normal", "direct", "indirect"};
    return names;
}

RenderSettings parseRender(const JsonReader& r) {
    // Keys of earlier versions: switches that moved to "experiments", and
    // options that measured not to pay and were removed.
    for (const char* k : {"volume_sampling", "sphere_caustics", "beam_directions", "glass_splitting", "adaptive"})
        if (r.has(k)) r.fail(k, str("moved to experiments.", k, " (a switch for A/B measurements; docs/scene-format.md)"));
    for (const char* k : {"majorant", "product_sampling", "guided_roulette"})
        if (r.has(k)) r.fail(k, "was removed (it did not pay at equal time; docs/benchmarks/history.md): delete the key");
    r.allowOnly({"method", "spp", "step", "shadow_step", "max_depth", "seed", "threads", "max_surface_bounces",
                 "pixel_jitter", "exposure", "li", "ray_samples", "aovs", "noise", "denoise"});
    RenderSettings s;
    {
        std::vector<std::string> names = {"auto"};
        for (Method m : allMethods()) names.push_back(methodName(m));
        const std::string name = r.choice("method", "auto", names);
        s.methodAuto = name == "auto";
        if (!s.methodAuto) parseMethod(name, s.method);
    }
    s.spp = r.integer("spp", s.spp, 1, 1 << 24);
    if (r.has("step")) s.step = float(r.positive("step", 1));
    if (r.has("shadow_step")) s.shadowStep = float(r.positive("shadow_step", 1));
    s.maxDepth = r.integer("max_depth", s.maxDepth, 1, 100000);
    if (r.has("seed")) {
        const Json& v = r.raw("seed");
        if (!v.is_number_integer() || v.get<long long>() < 0)
            r.fail("seed", str("must be a non-negative integer, got ", jsonExcerpt(v)));
        s.seed = v.get<uint64_t>();
    }
    s.threads = r.integer("threads", s.threads, 0, 4096);
    s.maxSurfaceBounces = r.integer("max_surface_bounces", s.maxSurfaceBounces, 0, 1000);
    s.pixelJitter = r.boolean("pixel_jitter", s.pixelJitter);
    s.exposure = float(r.numberIn("exposure", 0, -64, 64));
    parseLiSource(r.choice("li", liSourceName(s.li), {"path", "photons", "cache"}), s.li);
    s.raySamples = r.integer("ray_samples", s.raySamples, 1, 4096);
    if (r.has("aovs")) s.aovs = parseAovs(r);
    if (r.has("noise")) s.noise = float(r.numberIn("noise", 0, 1e-4, 10));
    {
        const std::string v = r.choice("denoise", "preview", {"preview", "on", "off"});
        s.denoise = v == "on" ? RenderSettings::Denoise::On
                    : v == "off" ? RenderSettings::Denoise::Off : RenderSettings::Denoise::Preview;
    }
    return s;
}

ExperimentSettings parseExperiments(const JsonReader& r) {
    r.allowOnly({"volume_sampling", "sphere_caustics", "beam_directions", "glass_splitting", "caustic_photons", "adaptive"});
    ExperimentSettings s;
    const std::string v = r.choice("volume_sampling", "mis", {"mis", "distance", "equiangular"});
    s.volumeSampling = v == "distance"      ? VolumeSampling::Distance
                       : v == "equiangular" ? VolumeSampling::Equiangular
                                            : VolumeSampling::Mis;
    s.sphereCaustics = r.boolean("sphere_caustics", s.sphereCaustics);
    s.beamDirections = r.boolean("beam_directions", s.beamDirections);
    s.glassSplitting = r.boolean("glass_splitting", s.glassSplitting);
    s.causticPhotons = r.boolean("caustic_photons", s.causticPhotons);
    s.adaptive = r.boolean("adaptive", s.adaptive);
    return s;
}

PhotonSettings parsePhotons(const JsonReader& r) {
    r.allowOnly({"count", "k", "seed", "progressive", "spp_per_pass", "alpha"});
    PhotonSettings s;
    if (r.has("seed")) {
        const Json& v = r.raw("seed");
        if (!v.is_number_integer() || v.get<long long>() < 0)
            r.fail("seed", str("must be a non-negative integer, got ", jsonExcerpt(v)));
        s.seed = v.get<int64_t>();
    }
    if (r.has("count")) {
        const Json& v = r.raw("count");
        if (!v.is_number_integer() || v.get<long long>() < 0 || v.get<long long>() > (1LL << 32))
            r.fail("count", str("must be an integer in [0, 2^32], got ", jsonExcerpt(v)));
        s.count = v.get<int64_t>();
    }
    s.k = r.integer("k", s.k, 1, 1024);
    s.progressive = r.boolean("progressive", s.progressive);
    s.sppPerPass = r.integer("spp_per_pass", s.sppPerPass, 0, 1 << 24);
    // alpha = 1 keeps the radius (no convergence); 0 would shrink it as fast
    // as the variance allows no averaging.
    if (r.has("alpha")) {
        double a = r.number("alpha");
        if (!(a > 0 && a < 1)) r.fail("alpha", str("must be in (0, 1), got ", a));
        s.alpha = float(a);
    }
    return s;
}

CacheSettings parseCache(const JsonReader& r) {
    r.allowOnly({"sh_order", "quality", "adaptive", "min_cell"});
    CacheSettings s;
    s.shOrder = r.integer("sh_order", s.shOrder, 0, 8);
    s.quality = float(r.positive("quality", s.quality));
    s.adaptive = r.boolean("adaptive", s.adaptive);
    if (r.has("min_cell")) s.minCell = float(r.positive("min_cell", 1));
    return s;
}

}  // namespace vdbmarch
