#include "estimators/ray_pdf.h"

#include <algorithm>
#include <cmath>

namespace vdbmarch {

namespace {
// Below this optical thickness a step's exponential is uniform to float precision.
constexpr double ThinStep = 1e-5;
}  // namespace

double truncatedExponentialPdf(float kappa, float len, float x) {
    const double tau = double(kappa) * double(len);
    if (tau < ThinStep) return 1.0 / double(len);
    return double(kappa) * std::exp(-double(kappa) * double(x)) / -std::expm1(-tau);
}

float sampleTruncatedExponential(float kappa, float len, double v) {
    const double tau = double(kappa) * double(len);
    double x = tau < ThinStep ? v * double(len) : -std::log1p(v * std::expm1(-tau)) / double(kappa);
    // Rounding must not push the sample out of its step.
    return float(std::min(std::max(x, 0.0), std::nextafter(double(len), 0.0)));
}

void RayPdf::build(const std::vector<PdfStep>& steps, const float* h, float defensive) {
    mSteps = &steps;
    mBase = mGuided = 0;
    for (size_t k = 0; k < steps.size(); ++k) {
        mBase += double(steps[k].base);
        if (h) mGuided += double(steps[k].base) * double(h[k]);
    }
    mCdf.assign(steps.size() + 1, 0.0);
    if (!(mBase > 0)) return;
    // Mixture weights: a guided share only when the histogram has any light.
    const double eps = h && mGuided > 0 ? double(defensive) : 1.0;
    double c = 0;
    for (size_t k = 0; k < steps.size(); ++k) {
        double p = eps * double(steps[k].base) / mBase;
        if (eps < 1) p += (1 - eps) * double(steps[k].base) * double(h[k]) / mGuided;
        c += p;
        mCdf[k + 1] = c;
    }
    for (size_t k = 1; k <= steps.size(); ++k) mCdf[k] /= c;  // exact 1 at the end despite rounding
    mCdf.back() = 1.0;
}

void RayPdf::sample(double u, int& step, float& offset, double& pdf) const {
    // The bin with cdf[k] <= u < cdf[k + 1]: it has positive width, so a
    // bin of probability 0 is never chosen.
    u = std::min(std::max(u, 0.0), std::nextafter(1.0, 0.0));
    size_t k = size_t(std::upper_bound(mCdf.begin(), mCdf.end(), u) - mCdf.begin()) - 1;
    const PdfStep& s = (*mSteps)[k];
    const double pk = mCdf[k + 1] - mCdf[k];
    const double v = std::min(std::max((u - mCdf[k]) / pk, 0.0), 1.0);
    const float x = sampleTruncatedExponential(s.kappa, s.len, v);
    step = int(k);
    offset = x;
    pdf = pk * truncatedExponentialPdf(s.kappa, s.len, x);
}

double RayPdf::pdf(int step, float offset) const {
    const PdfStep& s = (*mSteps)[size_t(step)];
    return stepProbability(step) * truncatedExponentialPdf(s.kappa, s.len, offset);
}

namespace {

double lightsDensity(const RayPdf::Lights& lights, float t) {
    double p = 0;
    for (const LightDistance& ld : lights) p += double(ld.choice) * ld.sampler.pdf(t);
    return p;
}

}  // namespace

bool RayPdf::locate(float t, int& step, float& offset) const {
    const std::vector<PdfStep>& steps = *mSteps;
    auto it = std::upper_bound(steps.begin(), steps.end(), t, [](float v, const PdfStep& s) { return v < s.t0; });
    if (it == steps.begin()) return false;
    --it;
    offset = t - it->t0;
    if (!(offset >= 0 && offset < it->len)) return false;
    step = int(it - steps.begin());
    return true;
}

bool RayPdf::sampleMixture(double u, const Mixture& mix, int& step, float& offset, double& p, float& t) const {
    const double a = mix.lights && !mix.lights->empty() ? mix.lightShare : 0.0;
    const double b = mix.folds && !mix.folds->empty() ? mix.foldShare : 0.0;
    if (!(a > 0) && !(b > 0)) {
        sample(u, step, offset, p);
        t = (*mSteps)[std::size_t(step)].t0 + offset;
        return true;
    }
    if (u < 1 - a - b) {  // P drew it, and gave its density
        sample(u / (1 - a - b), step, offset, p);
        t = (*mSteps)[std::size_t(step)].t0 + offset;
        if (b > 0 && !stepOffCrossing(*mix.folds, t, step, offset)) return false;
        p = mixturePdf(step, offset, mix, t);
        return p > 0;
    }
    if (u < 1 - b) {  // a light by its odds, then its sampler at the rest of u
        const Lights& lights = *mix.lights;
        double v = (u - (1 - a - b)) / a;
        std::size_t i = 0;
        for (; i + 1 < lights.size() && v >= double(lights[i].choice); ++i) v -= double(lights[i].choice);
        const float c = lights[i].choice;
        if (!(c > 0)) return false;
        if (!locate(lights[i].sampler.sample(float(std::clamp(v / double(c), 0.0, 1.0 - 1e-7))), step, offset))
            return false;
        t = (*mSteps)[std::size_t(step)].t0 + offset;
        if (b > 0 && !stepOffCrossing(*mix.folds, t, step, offset)) return false;
    } else {
        // The folds' t as drawn: t0 + offset may round it off a crossing,
        // where their density is sharpest.
        t = mix.folds->sample(float(std::clamp((u - (1 - b)) / b, 0.0, 1.0 - 1e-7)));
        if (!locate(t, step, offset)) return false;
    }
    p = mixturePdf(step, offset, mix, t);
    return p > 0;
}

bool RayPdf::stepOffCrossing(const FoldSampler& folds, float& t, int& step, float& offset) const {
    // A draw exactly on a fold's crossing moves to the next float
    // (FoldSampler::offCrossing).
    const float moved = folds.offCrossing(t);
    if (moved == t) return true;
    t = moved;
    return locate(t, step, offset);
}

double RayPdf::mixturePdf(int step, float offset, const Mixture& mix, float t) const {
    const double a = mix.lights && !mix.lights->empty() ? mix.lightShare : 0.0;
    const double b = mix.folds && !mix.folds->empty() ? mix.foldShare : 0.0;
    double p = pdf(step, offset);
    if (!(a > 0) && !(b > 0)) return p;
    p *= 1 - a - b;
    if (a > 0) p += a * lightsDensity(*mix.lights, t);
    if (b > 0) p += b * mix.folds->pdf(t);
    return p;
}

}  // namespace vdbmarch
