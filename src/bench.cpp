#include "bench.h"

#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <sstream>

#include "core/error.h"
#include "core/rng.h"
#include "image/atomic_file.h"
#include "image/exr_io.h"
#include "image/metrics.h"
#include "core/transform.h"
#include "render.h"

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

PowerFit fit(const std::vector<BenchRow>& rows) {
    PowerFit f;
    double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (const auto& r : rows) {
        if (!(r.seconds > 0 && r.rmse > 0)) continue;
        double x = std::log(r.seconds), y = std::log(r.rmse);
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

}  // namespace

BenchResult runBench(const SceneDesc& baseScene, const BenchOptions& o) {
    if (o.methods.empty()) throw InputError("bench: --methods is empty");
    if (o.budgets.empty()) throw InputError("bench: --budgets is empty");
    for (double b : o.vdbRenderSteps)
        if (!(b > 0)) throw InputError(str("bench: vdb_render step ", b, " must be positive"));
    for (double b : o.budgets)
        if (!(b > 0) || (!o.budgetSeconds && b != std::floor(b)))
            throw InputError(str("bench: budget ", b, " must be a positive ", o.budgetSeconds ? "number of seconds" : "whole number of samples"));
    ::mkdir(o.outDir.c_str(), 0755);
    checkWritable(o.outDir + "/bench.csv");
    BenchResult result;
    // Loaded once: every render below only changes the render settings.
    std::unique_ptr<Scene> scene = buildScene(baseScene);
    auto renderWith = [&](const std::string& method, int spp, uint64_t seed, const RenderOptions& ro) {
        scene->desc.render.method = method;
        scene->desc.render.spp = spp;
        scene->desc.render.seed = seed;
        return renderImage(*scene, ro);
    };

    // Reference: given, or the reference method at a high spp, cached by a
    // hash of the effective scene and spp. Rendered as two independent halves
    // so its own noise can be estimated: Var(mean) = Var(A - B) / 4.
    Image reference;
    if (!o.referencePath.empty()) {
        reference = readExr(o.referencePath);
        result.referenceImage = o.referencePath;
    } else {
        uint64_t h = hashValues(std::hash<std::string>()(baseScene.json.dump()), uint64_t(o.referenceSpp));
        char name[64];
        std::snprintf(name, sizeof(name), "reference_%016llx.exr", static_cast<unsigned long long>(h));
        std::string path = o.outDir + "/" + name, halfPath = path + ".half.exr";
        if (fileExists(path) && fileExists(halfPath)) {
            reference = readExr(path);
            Image a = readExr(halfPath);
            result.referenceNoiseRmse = compareImages(a, reference).rmse;  // |A - mean| = |A - B| / 2
        } else {
            std::fprintf(stderr, "bench: rendering the reference (%d spp, method reference)...\n", o.referenceSpp);
            Image halves[2];
            for (int i = 0; i < 2; ++i)
                halves[i] = renderWith("reference", std::max(1, o.referenceSpp / 2), 1000003u + uint64_t(i), {}).image;
            reference = Image(halves[0].width, halves[0].height);
            for (size_t i = 0; i < reference.rgba.size(); ++i)
                reference.rgba[i] = 0.5f * (halves[0].rgba[i] + halves[1].rgba[i]);
            result.referenceNoiseRmse = compareImages(halves[0], reference).rmse;
            writeExr(path, reference, {{"vdbmarch:method", "reference"}, {"vdbmarch:spp", std::to_string(o.referenceSpp)}});
            writeExr(halfPath, halves[0], {{"vdbmarch:method", "reference"}});
        }
        result.referenceImage = path;
    }

    for (const auto& method : o.methods) {
        for (double budget : method == "vdb_render" ? o.vdbRenderSteps : o.budgets) {
            if (method == "vdb_render") {
                // Budget = step in voxels; time = the whole command (load + render + write).
                std::string out = o.outDir + str("/vdb_render_step", budget, ".exr");
                std::string cmd = vdbRenderCommand(baseScene, *scene, budget, out);
                std::vector<double> times;
                for (int rep = 0; rep < std::max(1, o.repeats); ++rep) {
                    auto t0 = std::chrono::steady_clock::now();
                    if (std::system(cmd.c_str()) != 0)
                        throw IoError(str("bench: vdb_render failed (is libopenvdb-tools installed?): ", cmd));
                    times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
                }
                std::sort(times.begin(), times.end());
                ImageErrorStats e = compareImages(readExr(out), reference);
                BenchRow row{method, budget, times[times.size() / 2], e.rmse, e.relMse, 1};
                std::fprintf(stderr, "bench: %-10s step %-8g %9.3f s  rmse %.5g  relmse %.5g\n", method.c_str(), budget,
                             row.seconds, row.rmse, row.relMse);
                result.rows.push_back(row);
                continue;
            }
            RenderOptions ro;
            if (o.budgetSeconds) ro.timeBudget = budget;
            const int spp = o.budgetSeconds ? baseScene.render.spp : int(budget);
            std::vector<double> times;
            RenderResult last;
            for (int rep = 0; rep < std::max(1, o.repeats); ++rep) {
                last = renderWith(method, spp, baseScene.render.seed, ro);
                times.push_back(last.seconds);
            }
            std::sort(times.begin(), times.end());
            ImageErrorStats e = compareImages(last.image, reference);
            BenchRow row{method, budget, times[times.size() / 2], e.rmse, e.relMse, last.spp};
            std::fprintf(stderr, "bench: %-10s budget %-8g %4d spp %9.3f s  rmse %.5g  relmse %.5g\n", method.c_str(),
                         budget, row.spp, row.seconds, row.rmse, row.relMse);
            result.rows.push_back(row);
        }
    }

    // CSV
    std::ostringstream csv;
    csv << "method,budget,spp,seconds,rmse,relmse\n";
    for (const auto& r : result.rows)
        csv << r.method << "," << r.budget << "," << r.spp << "," << r.seconds << "," << r.rmse << "," << r.relMse << "\n";
    result.csvPath = o.outDir + "/bench.csv";
    writeTextFileAtomic(result.csvPath, csv.str());

    // Markdown: the measurements, then ratios between methods from power-law
    // fits error = c * time^b (log-log least squares per method), evaluated at
    // the geometric mean of all measured times.
    std::ostringstream md;
    md << "# vdbmarch bench\n\nReference image: `" << result.referenceImage << "`";
    if (result.referenceNoiseRmse > 0) md << " (its own estimated noise: RMSE " << result.referenceNoiseRmse << ")";
    md << "\n\n| method | budget | spp | seconds | RMSE | relMSE |\n|---|---|---|---|---|---|\n";
    for (const auto& r : result.rows)
        md << "| " << r.method << " | " << r.budget << " | " << r.spp << " | " << r.seconds << " | " << r.rmse << " | "
           << r.relMse << " |\n";
    double logSum = 0;
    int count = 0;
    for (const auto& r : result.rows)
        if (r.seconds > 0) {
            logSum += std::log(r.seconds);
            ++count;
        }
    double tMid = count ? std::exp(logSum / count) : 1;
    std::vector<PowerFit> fits;
    for (const auto& m : o.methods) {
        std::vector<BenchRow> mine;
        for (const auto& r : result.rows)
            if (r.method == m) mine.push_back(r);
        fits.push_back(fit(mine));
    }
    md << "\nFits RMSE = c * seconds^b and ratios at " << tMid << " s (row method / column method):\n\n";
    md << "| method | b | RMSE at " << tMid << " s |";
    for (const auto& m : o.methods) md << " equal-time error ratio vs " << m << " | equal-error time ratio vs " << m << " |";
    md << "\n|---|---|---|";
    for (size_t i = 0; i < o.methods.size(); ++i) md << "---|---|";
    md << "\n";
    for (size_t i = 0; i < o.methods.size(); ++i) {
        md << "| " << o.methods[i] << " | ";
        if (!fits[i].ok) {
            md << "n/a | n/a |";
            for (size_t j = 0; j < o.methods.size(); ++j) md << " n/a | n/a |";
            md << "\n";
            continue;
        }
        double ei = fits[i].at(tMid);
        md << fits[i].b << " | " << ei << " |";
        for (size_t j = 0; j < o.methods.size(); ++j) {
            if (!fits[j].ok) {
                md << " n/a | n/a |";
                continue;
            }
            md << " " << ei / fits[j].at(tMid) << " | " << tMid / fits[j].timeFor(ei) << " |";
        }
        md << "\n";
    }
    result.tablePath = o.outDir + "/bench.md";
    writeTextFileAtomic(result.tablePath, md.str());

    // Plot with gnuplot when it is installed (tools/plot_bench.gp).
    result.plotPath = o.outDir + "/bench.png";
    std::string script = std::string(VDBMARCH_DATA_DIR) + "/tools/plot_bench.gp";
    std::string cmd = "command -v gnuplot >/dev/null 2>&1 && gnuplot -e \"csv='" + result.csvPath + "'; out='" +
                      result.plotPath + ".tmp.png'\" '" + script + "' && mv '" + result.plotPath + ".tmp.png' '" +
                      result.plotPath + "'";
    if (std::system(cmd.c_str()) != 0) {
        warn(str("bench: no plot written (gnuplot missing or failed; Debian package gnuplot-nox)"));
        result.plotPath.clear();
    }
    return result;
}

}  // namespace vdbmarch
