#include "transport/phase.h"

#include "core/sampling.h"

namespace vdbmarch {

Color PhaseMixture::eval(float cosTheta) const {
    if (count == 1) return Color(hgPhase(cosTheta, g[0]));
    Color total(0), f(0);
    for (int i = 0; i < count; ++i) total += sigmaS[i];
    for (int i = 0; i < count; ++i) f += sigmaS[i] * hgPhase(cosTheta, g[i]);
    for (int c = 0; c < 3; ++c) f[c] = total[c] > 0 ? f[c] / total[c] : 0.f;
    return f;
}

float PhaseMixture::pdf(float cosTheta) const {
    if (count == 1) return hgPhase(cosTheta, g[0]);
    double total = 0, p = 0;
    for (int i = 0; i < count; ++i) {
        const double w = average(sigmaS[i]);
        total += w;
        p += w * hgPhase(cosTheta, g[i]);
    }
    return total > 0 ? float(p / total) : 0.f;
}

Vec3 PhaseMixture::sample(const Vec3& d, float u0, float u1, float u2, Color& weight, float& pdfOut) const {
    int k = 0;
    if (count > 1) {
        float total = 0;
        for (int i = 0; i < count; ++i) total += average(sigmaS[i]);
        float pick = u0 * total;
        while (k + 1 < count && pick >= average(sigmaS[k])) pick -= average(sigmaS[k++]);
    }
    const Vec3 wi = directionAround(d, sampleHgCosTheta(u1, g[k]), u2);
    const float c = dot(wi, d);
    pdfOut = pdf(c);
    if (count > 1 && pdfOut > 0) weight *= eval(c) / pdfOut;
    return wi;
}

void PhaseMixture::legendreWeights(int order, float* out) const {
    for (int l = 0; l <= order; ++l) out[l] = 0;
    if (count == 0) return;
    double total = 0;
    for (int i = 0; i < count; ++i) total += average(sigmaS[i]);
    if (!(total > 0)) return;
    for (int i = 0; i < count; ++i) {
        const double w = average(sigmaS[i]) / total;
        double gl = 1;
        for (int l = 0; l <= order; ++l, gl *= g[i]) out[l] += float(w * gl);
    }
}

float PhaseMixture::meanPhaseValue() const {
    auto lobe = [](double gi) {
        const double g2 = gi * gi;
        return (1 + g2) / ((1 - g2) * (1 - g2));
    };
    if (count == 1) return float(lobe(g[0]));
    double total = 0, m = 0;
    for (int i = 0; i < count; ++i) {
        const double w = average(sigmaS[i]);
        total += w;
        m += w * lobe(g[i]);
    }
    return total > 0 ? float(m / total) : 1.f;
}

bool PhaseMixture::isotropic() const {
    for (int i = 0; i < count; ++i)
        if (g[i] != 0) return false;
    return true;
}

}  // namespace vdbmarch
