#include "app/bench.h"

#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <sstream>

#include "app/method_pilot.h"
#include "core/error.h"
#include "core/hash.h"
#include "core/rng.h"
#include "core/atomic_file.h"
#include "image/exr_io.h"
#include "image/metrics.h"
#include "image/png_io.h"
#include "core/transform.h"
#include "parse/auto_method.h"
#include "render/render.h"

namespace vdbmarch {

namespace {

bool fileExists(const std::string& p) {
    struct stat st;
    return ::stat(p.c_str(), &st) == 0;
}

// Least-squares line log(rmse) = a + b log(seconds) for one method.
struct PowerFit {
    double a = 0, b = 0;
    bool ok = false;
    double at(double seconds) const { return std::exp(a + b * std::log(seconds)); }
    double timeFor(double rmse) const { return std::exp((std::log(rmse) - a) / b); }
};

PowerFit fit(const std::vector<BenchRow>& rows, double BenchRow::*error = &BenchRow::rmse) {
    PowerFit f;
    double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (const auto& r : rows) {
        if (!(r.seconds > 0 && r.*error > 0)) continue;
        double x = std::log(r.seconds), y = std::log(r.*error);
        n += 1;
        sx += x;
        sy += y;
        sxx += x * x;
        sxy += x * y;
    }
    double det = n * sxx - sx * sx;
    if (n >= 2 && det > 1e-12) {
        f.b = (n * sxy - sx * sy) / det;
        f.a = (sy - f.b * sx) / n;
        f.ok = f.b < 0;
    }
    return f;
}

// The external peer: OpenVDB's vdb_render, single scattering, for scenes it
// can express (one VDB medium without transform or emission, isotropic, one
// directional light, no surfaces, black background, perspective camera). The
// budget is its step (and shadow step) in voxels. Mapping derived and checked
// in bench/vdb_render_notes.md: per-voxel coefficients = sigma * h, light
// colour = irradiance / (4 pi), -fov is horizontal, -light points at the light.
std::string vdbRenderCommand(const SceneDesc& d, const Scene& scene, double stepVoxels, const std::string& out) {
    auto refuse = [&](const std::string& why) {
        throw InputError(str(d.file, ": method vdb_render cannot render this scene: ", why));
    };
    if (d.media.size() != 1 || d.media[0].type != MediumDesc::Type::Vdb) refuse("it needs exactly one vdb medium");
    const MediumDesc& m = d.media[0];
    if (m.hasEmission) refuse("emission");
    if (m.g != 0) refuse(str("g = ", m.g, " (vdb_render is isotropic)"));
    if (!Transform(m.transform).isIdentity()) refuse("a medium transform");
    if (d.lights.size() != 1 || d.lights[0].type != LightDesc::Type::Directional) refuse("it needs exactly one directional light");
    if (!d.surfaces.empty()) refuse("surfaces");
    if (!isBlack(d.background)) refuse("a non-black background");
    if (!d.environment.file.empty()) refuse("an environment map");
    if (d.camera.type != CameraDesc::Type::Perspective) refuse("an orthographic camera");
    const double h = scene.media[0]->minVoxelSize();
    const CameraDesc& c = d.camera;
    double hfov = 2 * std::atan(std::tan(double(radians(c.fovDeg)) / 2) * c.width / c.height) * 180 / M_PI;
    Vec3 toLight = -d.lights[0].direction;
    Color col = d.lights[0].irradiance / (4 * Pi);
    return str("vdb_render '", m.file, "' '", out, "' -name '", m.grid, "' -res ", c.width, "x", c.height, " -translate ",
               c.position.x, ",", c.position.y, ",", c.position.z, " -lookat ", c.lookAt.x, ",", c.lookAt.y, ",",
               c.lookAt.z, " -up ", c.up.x, ",", c.up.y, ",", c.up.z, " -fov ", hfov, " -gain 0 -cutoff 1e-10",
               " -scatter ", m.sigma_s.x * m.densityScale * h, ",", m.sigma_s.y * m.densityScale * h, ",",
               m.sigma_s.z * m.densityScale * h, " -absorb ", m.sigma_a.x * m.densityScale * h, ",",
               m.sigma_a.y * m.densityScale * h, ",", m.sigma_a.z * m.densityScale * h, " -light ", toLight.x, ",",
               toLight.y, ",", toLight.z, ",", col.x, ",", col.y, ",", col.z, " -step ", stepVoxels, " -shadowstep ",
               stepVoxels, " -compression none -cpus ", d.render.threads, " >/dev/null 2>&1");
}

// Source pixels and weights (summing to 1) of each output pixel along one axis
// when `from` pixels are resampled to `to` by area averaging.
struct Tap {
    int index;
    float weight;
};
std::vector<std::vector<Tap>> boxTaps(int from, int to) {
    std::vector<std::vector<Tap>> taps(static_cast<size_t>(to));
    const double scale = double(from) / double(to);
    for (int o = 0; o < to; ++o) {
        const double lo = o * scale, hi = (o + 1) * scale;
        for (int i = int(std::floor(lo)); i < std::min(from, int(std::ceil(hi))); ++i) {
            double w = std::min(hi, i + 1.0) - std::max(lo, double(i));
            if (w > 0) taps[size_t(o)].push_back({i, float(w / (hi - lo))});
        }
    }
    return taps;
}

// Index of the run with the median time (the upper one for an even count, as
// the reported seconds).
size_t medianRun(const std::vector<double>& times) {
    std::vector<size_t> order(times.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return times[a] < times[b]; });
    return order[order.size() / 2];
}

// tiles[row][column]; an empty Image leaves its cell in the separator colour.
void writeStrip(const std::string& path, const std::vector<std::vector<Image>>& tiles, int columns,
                bool referenceColumn, int tileW, int tileH, float exposure) {
    auto columnX = [&](int c) {
        int gapAfterReference = referenceColumn && c > 0 ? StripReferenceGap - StripSeparator : 0;
        return c * (tileW + StripSeparator) + gapAfterReference;
    };
    const int width = columnX(columns - 1) + tileW;
    const int height = int(tiles.size()) * (tileH + StripSeparator) - StripSeparator;
    std::vector<uint8_t> rgb(size_t(width) * size_t(height) * 3, StripSeparatorValue);
    for (size_t r = 0; r < tiles.size(); ++r)
        for (size_t c = 0; c < tiles[r].size(); ++c) {
            const Image& t = tiles[r][c];
            if (t.empty()) continue;
            std::vector<uint8_t> tile = toSrgb8(t, exposure);
            const int x0 = columnX(int(c)), y0 = int(r) * (tileH + StripSeparator);
            for (int y = 0; y < tileH; ++y)
                std::copy_n(&tile[size_t(y) * size_t(tileW) * 3], size_t(tileW) * 3,
                            &rgb[(size_t(y0 + y) * size_t(width) + size_t(x0)) * 3]);
        }
    writePngRgb8(path, width, height, rgb);
}

}  // namespace

Image downscaleBox(const Image& img, int width, int height) {
    if (width <= 0 || height <= 0 || img.empty())
        throw InputError(str("cannot resample a ", img.width, "x", img.height, " image to ", width, "x", height));
    // Separable: rows first (img.width -> width), then columns.
    const auto tx = boxTaps(img.width, width), ty = boxTaps(img.height, height);
    Image rows(width, img.height), out(width, height);
    const size_t inRow = size_t(img.width) * 4, outRow = size_t(width) * 4;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < width; ++x)
            for (const Tap& t : tx[size_t(x)])
                for (size_t c = 0; c < 4; ++c) {
                    float v = img.rgba[size_t(y) * inRow + size_t(t.index) * 4 + c];
                    rows.rgba[size_t(y) * outRow + size_t(x) * 4 + c] += std::isfinite(v) ? t.weight * v : 0.f;
                }
    for (int y = 0; y < height; ++y)
        for (const Tap& t : ty[size_t(y)])
            for (size_t i = 0; i < outRow; ++i)
                out.rgba[size_t(y) * outRow + i] += t.weight * rows.rgba[size_t(t.index) * outRow + i];
    return out;
}

namespace {

// What a bench compares: vdb_render (budgets are march steps in voxels) or
// one of vdbmarch's methods (budgets are samples or seconds).
struct BenchMethod {
    std::string name;
    bool vdbRender = false;
    bool automatic = false;  // "auto": the rule's pick, by pilots in timed runs (app/method_pilot.h)
    Method method = Method::Reference;
    const std::vector<double>& budgets(const BenchOptions& o) const { return vdbRender ? o.vdbRenderSteps : o.budgets; }
};

// The strip's columns (the reference's, then the longest budget list) and
// its gaps in pixels.
struct StripLayout {
    int columns = 0, gaps = 0;
};

// Refuses bad options before anything renders; the methods by name.
std::vector<BenchMethod> checkOptions(const BenchOptions& o, StripLayout& strip) {
    if (o.methods.empty()) throw InputError("bench: --methods is empty");
    if (o.budgets.empty()) throw InputError("bench: --budgets is empty");
    for (double b : o.vdbRenderSteps)
        if (!(b > 0)) throw InputError(str("bench: vdb_render step ", b, " must be positive"));
    for (double b : o.budgets)
        if (!(b > 0) || (!o.budgetSeconds && b != std::floor(b)))
            throw InputError(str("bench: budget ", b, " must be a positive ", o.budgetSeconds ? "number of seconds" : "whole number of samples"));
    std::vector<BenchMethod> methods;
    for (const std::string& name : o.methods) {
        BenchMethod m{name, name == "vdb_render", name == "auto"};
        if (!m.vdbRender && !m.automatic && !parseMethod(name, m.method))
            throw InputError(str("bench: unknown method \"", name, "\" (", methodList(), ", auto or vdb_render)"));
        methods.push_back(m);
    }
    size_t most = 0;
    for (const BenchMethod& m : methods) most = std::max(most, m.budgets(o).size());
    strip.columns = (o.stripReference ? 1 : 0) + int(most);
    strip.gaps = (strip.columns - 1) * StripSeparator + (o.stripReference ? StripReferenceGap - StripSeparator : 0);
    if (!o.stripPath.empty() && o.stripMaxWidth < strip.columns + strip.gaps)
        throw InputError(str("bench: --strip-width ", o.stripMaxWidth, " is too small for ", strip.columns,
                             " strip columns (at least ", strip.columns + strip.gaps, " pixels)"));
    return methods;
}

// Renders `scene` with `method` at `spp` and `seed` (only the render
// settings change between the bench's renders: the media load once). `auto`
// renders as `vdbmarch render` does: the rule's pick, or in a timed run
// the pick of pilots, whose time counts.
RenderResult renderWith(Scene& scene, const BenchMethod& method, int spp, uint64_t seed, RenderOptions ro) {
    scene.desc.render.method = method.method;
    scene.desc.render.spp = spp;
    scene.desc.render.seed = seed;
    if (!method.automatic) return renderImage(scene, ro);
    scene.desc.render.method = chooseMethod(scene.desc, scene.desc.render.methodReason);
    if (!(ro.timeBudget > 0)) return renderImage(scene, ro);
    ro.runStart = std::chrono::steady_clock::now();
    MethodPilot pilot;
    return renderByPilots(scene, ro, pilot);
}

// The reference: given, or the reference method at a high spp, cached in
// outDir by a hash of the effective scene and spp. Rendered as two
// independent halves so its own noise can be estimated: Var(mean) =
// Var(A - B) / 4.
Image benchReference(Scene& scene, const SceneDesc& baseScene, const BenchOptions& o, BenchResult& result) {
    if (!o.referencePath.empty()) {
        result.referenceImage = o.referencePath;
        return readExr(o.referencePath);
    }
    const uint64_t h = hashValues(fnv1a64(baseScene.jsonText), uint64_t(o.referenceSpp));
    char name[64];
    std::snprintf(name, sizeof(name), "reference_%016llx.exr", static_cast<unsigned long long>(h));
    const std::string path = o.outDir + "/" + name, halfPath = path + ".half.exr";
    result.referenceImage = path;
    Image reference;
    if (fileExists(path) && fileExists(halfPath)) {
        reference = readExr(path);
        Image a = readExr(halfPath);
        result.referenceNoiseRmse = compareImages(a, reference).rmse;  // |A - mean| = |A - B| / 2
        result.referenceNoiseLowFreq = lowFrequencyError(a, reference);
        return reference;
    }
    std::fprintf(stderr, "bench: rendering the reference (%d spp, method reference)...\n", o.referenceSpp);
    // The truth is unbiased: sphere lights' caustics by paths, not photons.
    struct PathCaustics {
        Scene& s;
        const bool was = s.sphereLightCausticPhotons;
        ~PathCaustics() { s.sphereLightCausticPhotons = was; }
    } pathCaustics{scene};
    scene.sphereLightCausticPhotons = false;
    Image halves[2];
    for (int i = 0; i < 2; ++i)
        halves[i] = renderWith(scene, BenchMethod{"reference"}, std::max(1, o.referenceSpp / 2), 1000003u + uint64_t(i), {}).image;
    reference = Image(halves[0].width, halves[0].height);
    for (size_t i = 0; i < reference.rgba.size(); ++i) reference.rgba[i] = 0.5f * (halves[0].rgba[i] + halves[1].rgba[i]);
    result.referenceNoiseRmse = compareImages(halves[0], reference).rmse;
    result.referenceNoiseLowFreq = lowFrequencyError(halves[0], reference);
    writeExr(path, reference, {{"vdbmarch:method", "reference"}, {"vdbmarch:spp", std::to_string(o.referenceSpp)}});
    writeExr(halfPath, halves[0], {{"vdbmarch:method", "reference"}});
    return reference;
}

// One vdb_render run per repeat; budget = step in voxels; time = the whole
// command (load + render + write). vdb_render is deterministic: the last
// run's file is the median run's image.
Image runVdbRender(const SceneDesc& baseScene, const Scene& scene, const BenchOptions& o, double step, double& seconds) {
    const std::string out = o.outDir + str("/vdb_render_step", step, ".exr");
    const std::string cmd = vdbRenderCommand(baseScene, scene, step, out);
    std::vector<double> times;
    for (int rep = 0; rep < std::max(1, o.repeats); ++rep) {
        auto t0 = std::chrono::steady_clock::now();
        if (std::system(cmd.c_str()) != 0)
            throw IoError(str("bench: vdb_render failed (is libopenvdb-tools installed?): ", cmd));
        times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    seconds = times[medianRun(times)];
    return readExr(out);
}

// The error of `img` against the reference: RMSE, relMSE, the relative
// error's spread and the low-frequency error.
BenchRow measureRow(const std::string& method, double budget, double seconds, int spp, const Image& img,
                    const Image& reference, BenchResult& result) {
    const ImageErrorStats e = compareImages(img, reference);
    BenchRow row{method, budget, seconds, e.rmse, e.relMse, spp};
    const RelErrorSpread sp = relativeErrorSpread(img, reference, BenchSpreadMinAlpha);
    row.relP50 = sp.p50;
    row.relP95 = sp.p95;
    row.relSpread = sp.ratio;
    row.lowFreq = lowFrequencyError(img, reference);
    result.spreadEps = sp.eps;
    result.spreadPixels = sp.pixels;
    return row;
}

std::string benchCsv(const std::vector<BenchRow>& rows) {
    std::ostringstream csv;
    csv << "method,budget,spp,seconds,rmse,relmse,rel_p50,rel_p95,rel_p95_over_p50,low_freq\n";
    for (const auto& r : rows)
        csv << r.method << "," << r.budget << "," << r.spp << "," << r.seconds << "," << r.rmse << "," << r.relMse
            << "," << r.relP50 << "," << r.relP95 << "," << r.relSpread << "," << r.lowFreq << "\n";
    return csv.str();
}

// The measurements as a Markdown table, with what its columns mean.
void writeMeasurements(std::ostringstream& md, const BenchResult& result) {
    md << "# vdbmarch bench\n\nReference image: `" << result.referenceImage << "`";
    if (result.referenceNoiseRmse > 0)
        md << " (its own estimated noise: RMSE " << result.referenceNoiseRmse << ", LF error "
           << result.referenceNoiseLowFreq << ")";
    md << "\n\n| method | budget | spp | seconds | RMSE | relMSE | LF error | rel. error p50 | rel. error p95 | p95/p50 |\n"
          "|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& r : result.rows)
        md << "| " << r.method << " | " << r.budget << " | " << r.spp << " | " << r.seconds << " | " << r.rmse << " | "
           << r.relMse << " | " << r.lowFreq << " | " << r.relP50 << " | " << r.relP95 << " | " << r.relSpread << " |\n";
    md << "\nLF error: RMSE of 8x8 block means of the image and the reference, over the reference's mean: bias and "
          "blotches show there, pixel noise averages out.\n";
    md << "\nPer-pixel relative error e = mean over RGB of |I - R| / (R + eps), eps = " << RelSpreadEpsilonFraction
       << " x the reference mean = " << result.spreadEps << ", over the " << result.spreadPixels
       << " pixels where the reference's alpha >= " << BenchSpreadMinAlpha
       << " (medium or surface in view); p50 and p95 are its nearest-rank percentiles. p95/p50 measures how unevenly "
          "the error is spread over the image: lower is more homogeneous.\n";
}

// Ratios between methods from power-law fits error = c * time^b (log-log
// least squares per method), evaluated at the geometric mean of all
// measured times.
void writeRatios(std::ostringstream& md, const BenchResult& result, const std::vector<std::string>& methods) {
    double logSum = 0;
    int count = 0;
    for (const auto& r : result.rows)
        if (r.seconds > 0) {
            logSum += std::log(r.seconds);
            ++count;
        }
    const double tMid = count ? std::exp(logSum / count) : 1;
    std::vector<PowerFit> fits;
    for (const auto& m : methods) {
        std::vector<BenchRow> mine;
        for (const auto& r : result.rows)
            if (r.method == m) mine.push_back(r);
        fits.push_back(fit(mine));
    }
    md << "\nFits RMSE = c * seconds^b and ratios at " << tMid << " s (row method / column method):\n\n";
    md << "| method | b | RMSE at " << tMid << " s |";
    for (const auto& m : methods) md << " equal-time error ratio vs " << m << " | equal-error time ratio vs " << m << " |";
    md << "\n|---|---|---|";
    for (size_t i = 0; i < methods.size(); ++i) md << "---|---|";
    md << "\n";
    for (size_t i = 0; i < methods.size(); ++i) {
        md << "| " << methods[i] << " | ";
        if (!fits[i].ok) {
            md << "n/a | n/a |";
            for (size_t j = 0; j < methods.size(); ++j) md << " n/a | n/a |";
            md << "\n";
            continue;
        }
        const double ei = fits[i].at(tMid);
        md << fits[i].b << " | " << ei << " |";
        for (size_t j = 0; j < methods.size(); ++j) {
            if (!fits[j].ok) {
                md << " n/a | n/a |";
                continue;
            }
            md << " " << ei / fits[j].at(tMid) << " | " << tMid / fits[j].timeFor(ei) << " |";
        }
        md << "\n";
    }
}

// Convergence: the slopes of log error against log time, and the error at
// the largest budget over the error at the budget closest to a quarter of
// it (1/2 for noise falling as 1/sqrt(time); near 1: a plateau). The
// reference's own noise is taken out in quadrature first, so that a method
// does not look stuck at the floor of an imperfect truth.
void writeConvergence(std::ostringstream& md, const BenchResult& result, const std::vector<std::string>& methods) {
    auto net = [](double e, double noise) { return std::sqrt(std::max(0.0, e * e - noise * noise)); };
    md << "\nConvergence per method: slopes b of RMSE and LF error against time (-0.5 for unbiased noise; near 0: "
          "a plateau), and error at the last budget over error at a quarter of it, both net of the reference's own "
          "noise (subtracted in quadrature):\n\n"
          "| method | b (RMSE) | b (LF) | RMSE ratio | LF ratio | |\n|---|---|---|---|---|---|\n";
    for (const auto& m : methods) {
        std::vector<BenchRow> mine;
        for (const auto& r : result.rows)
            if (r.method == m) {
                mine.push_back(r);
                mine.back().rmse = net(r.rmse, result.referenceNoiseRmse);
                mine.back().lowFreq = net(r.lowFreq, result.referenceNoiseLowFreq);
            }
        if (mine.size() < 2) continue;
        const PowerFit fr = fit(mine), fl = fit(mine, &BenchRow::lowFreq);
        const BenchRow& last = mine.back();
        const BenchRow* quarter = &mine.front();
        for (const auto& r : mine)
            if (std::fabs(std::log(r.budget / (last.budget / 4))) < std::fabs(std::log(quarter->budget / (last.budget / 4))))
                quarter = &r;
        const double rr = last.rmse / quarter->rmse, lr = last.lowFreq / quarter->lowFreq;
        md << "| " << m << " | " << (fr.ok ? str(fr.b) : "n/a") << " | " << (fl.ok ? str(fl.b) : "n/a") << " | " << rr
           << " | " << lr << " | " << (rr > 0.6 || lr > 0.6 ? "**plateau** (ratio > 0.6)" : "converging") << " |\n";
    }
}

// Plots with gnuplot when it is installed (tools/plot_bench.gp); the path
// written, or empty.
std::string plotBench(const std::string& csvPath, const std::string& plotPath) {
    const std::string script = std::string(VDBMARCH_DATA_DIR) + "/tools/plot_bench.gp";
    const std::string cmd = "command -v gnuplot >/dev/null 2>&1 && gnuplot -e \"csv='" + csvPath + "'; out='" +
                            plotPath + ".tmp.png'\" '" + script + "' && mv '" + plotPath + ".tmp.png' '" + plotPath + "'";
    if (std::system(cmd.c_str()) == 0) return plotPath;
    warn(str("bench: no plot written (gnuplot missing or failed; Debian package gnuplot-nox)"));
    return "";
}

}  // namespace

BenchResult runBench(const SceneDesc& baseScene, const BenchOptions& o) {
    StripLayout strip;
    const std::vector<BenchMethod> methods = checkOptions(o, strip);
    ::mkdir(o.outDir.c_str(), 0755);
    checkWritable(o.outDir + "/bench.csv");
    if (!o.stripPath.empty()) checkWritable(o.stripPath);
    BenchResult result;
    std::unique_ptr<Scene> scene = buildScene(baseScene);  // loaded once
    const Image reference = benchReference(*scene, baseScene, o, result);

    // Strip tiles keep the image size unless the strip would exceed its
    // width; downscaled as soon as rendered, so large benches do not hold
    // every image.
    int tileW = reference.width, tileH = reference.height;
    if (tileW * strip.columns + strip.gaps > o.stripMaxWidth) {
        tileW = std::max(1, (o.stripMaxWidth - strip.gaps) / strip.columns);
        tileH = std::max(1, int(std::lround(double(reference.height) * tileW / reference.width)));
    }
    auto makeTile = [&](const Image& img) {
        return tileW == img.width && tileH == img.height ? img : downscaleBox(img, tileW, tileH);
    };
    std::vector<std::vector<Image>> tiles(methods.size());
    if (!o.stripPath.empty() && o.stripReference) {
        const Image referenceTile = makeTile(reference);
        for (auto& row : tiles) row.push_back(referenceTile);
    }

    // ---- The runs: each method at each budget, the median-time run measured.
    for (size_t mi = 0; mi < methods.size(); ++mi) {
        const BenchMethod& method = methods[mi];
        for (double budget : method.budgets(o)) {
            BenchRow row;
            if (method.vdbRender) {
                double seconds = 0;
                const Image img = runVdbRender(baseScene, *scene, o, budget, seconds);
                row = measureRow(method.name, budget, seconds, 1, img, reference, result);
                if (!o.stripPath.empty()) tiles[mi].push_back(makeTile(img));
                std::fprintf(stderr, "bench: %-10s step %-8g %9.3f s  rmse %.5g  relmse %.5g  rel p95/p50 %.4g\n",
                             method.name.c_str(), budget, row.seconds, row.rmse, row.relMse, row.relSpread);
            } else {
                RenderOptions ro;
                if (o.budgetSeconds) ro.timeBudget = budget;
                const int spp = o.budgetSeconds ? baseScene.render.spp : int(budget);
                // All runs are kept until the median-time one is known: with
                // --seconds their sample counts, hence images, may differ.
                std::vector<double> times;
                std::vector<RenderResult> runs;
                for (int rep = 0; rep < std::max(1, o.repeats); ++rep) {
                    runs.push_back(renderWith(*scene, method, spp, baseScene.render.seed, ro));
                    times.push_back(runs.back().seconds);
                }
                const RenderResult& med = runs[medianRun(times)];
                row = measureRow(method.name, budget, med.seconds, med.spp, med.image, reference, result);
                if (!o.stripPath.empty()) tiles[mi].push_back(makeTile(med.image));
                std::fprintf(stderr,
                             "bench: %-10s budget %-8g %4d spp %9.3f s  rmse %.5g  relmse %.5g  LF %.4g  rel p95/p50 %.4g\n",
                             method.name.c_str(), budget, row.spp, row.seconds, row.rmse, row.relMse, row.lowFreq,
                             row.relSpread);
            }
            result.rows.push_back(row);
        }
    }

    // ---- The outputs: CSV, the Markdown table, the strip, the plot.
    result.csvPath = o.outDir + "/bench.csv";
    writeTextFileAtomic(result.csvPath, benchCsv(result.rows));
    std::ostringstream md;
    writeMeasurements(md, result);
    writeRatios(md, result, o.methods);
    writeConvergence(md, result, o.methods);
    if (!o.stripPath.empty()) {
        writeStrip(o.stripPath, tiles, strip.columns, o.stripReference, tileW, tileH, baseScene.render.exposure);
        result.stripPath = o.stripPath;
        result.stripRows = int(tiles.size());
        result.stripColumns = strip.columns;
        result.tileWidth = tileW;
        result.tileHeight = tileH;
        std::string names;
        for (const auto& m : o.methods) names += (names.empty() ? "" : ", ") + m;
        md << "\nImage strip: `" << o.stripPath << "` (rows: " << names << "; columns: "
           << (o.stripReference ? "the reference, then " : "") << "the budgets in order; " << tileW << "x" << tileH
           << " tiles, exposure " << baseScene.render.exposure << " stops)\n";
    }
    result.tablePath = o.outDir + "/bench.md";
    writeTextFileAtomic(result.tablePath, md.str());
    result.plotPath = plotBench(result.csvPath, o.outDir + "/bench.png");
    return result;
}

}  // namespace vdbmarch
