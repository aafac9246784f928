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
    for (const ThreadContext::LightDistance& ld : lights) p += double(ld.choice) * ld.sampler.pdf(t);
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

double RayPdf::pdfWithLights(int step, float offset, double a, const Lights& lights) const {
    const double p = pdf(step, offset);
    if (!(a > 0)) return p;
    return (1 - a) * p + a * lightsDensity(lights, (*mSteps)[std::size_t(step)].t0 + offset);
}

bool RayPdf::sampleWithLights(double u, double a, const Lights& lights, int& step, float& offset, double& p) const {
    if (!(a > 0) || lights.empty()) {
        sample(u, step, offset, p);
        return true;
    }
    if (u < 1 - a) {  // P drew it, and gave its density
        sample(u / (1 - a), step, offset, p);
        p = (1 - a) * p + a * lightsDensity(lights, (*mSteps)[std::size_t(step)].t0 + offset);
        return p > 0;
    }
    // A light by its odds, then its sampler at the rest of u.
    double v = (u - (1 - a)) / a;
    std::size_t i = 0;
    for (; i + 1 < lights.size() && v >= double(lights[i].choice); ++i) v -= double(lights[i].choice);
    const float c = lights[i].choice;
    if (!(c > 0)) return false;
    const float t = lights[i].sampler.sample(float(std::clamp(v / double(c), 0.0, 1.0 - 1e-7)));
    if (!locate(t, step, offset)) return false;
    p = pdfWithLights(step, offset, a, lights);
    return p > 0;
}

}  // namespace vdbmarch
