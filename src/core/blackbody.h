// Blackbody emission colours: Planck's law integrated against the CIE 1931
// 2-degree colour matching functions, converted to linear Rec.709 (the
// renderer's RGB). The colour is normalised to luminance 1 (chromaticity
// only); the brightness follows the Stefan-Boltzmann law scaled as Cycles'
// Principled Volume does. docs/numerics.md, "Blackbody emission", derives it.
#pragma once

#include "core/math.h"

namespace vdbmarch {

struct Xyz {
    double X = 0, Y = 0, Z = 0;
};

// Planck's spectral radiance B(lambda, T) in W / (m^2 sr m) for a wavelength
// in metres; 0 for T <= 0.
double planckRadiance(double lambdaMetres, double kelvin);

// Tristimulus values of a blackbody at `kelvin`, summed over the CIE table at
// 5 nm (360-830 nm), scaled so that Y = 1. Exact (no table lookup), slow:
// ~100 exponentials. kelvin must be > 0.
Xyz blackbodyXyz(double kelvin);

// CIE XYZ to linear Rec.709 / sRGB primaries with the D65 white (derived
// from the BT.709 primaries and white point).
Color xyzToRec709(const Xyz& xyz);

// Luminance-1 linear Rec.709 colour of a blackbody, exact (slow): negative
// components (chromaticities outside the Rec.709 gamut, below about 1900 K)
// are clipped to 0 before the colour is rescaled to luminance 1.
Color blackbodyColorExact(double kelvin);

// The same from a precomputed table, linear in reciprocal temperature (mired)
// between BlackbodyMinKelvin and BlackbodyMaxKelvin; clamped to the end
// colours outside. Cheap: one division and a lerp.
constexpr float BlackbodyMinKelvin = 500, BlackbodyMaxKelvin = 40000;
Color blackbodyColor(float kelvin);

// Luminance of the emitted radiance at `kelvin` for intensity 1: the
// Stefan-Boltzmann total radiance sigma T^4 / pi, times 1e-6 (the scale of
// Cycles' Principled Volume, so that Y = 1 at about 2728 K). 0 for T <= 0.
inline float blackbodyLuminance(float kelvin) {
    constexpr float k = float(5.670374419e-8 * 1e-6 / 3.14159265358979323846);
    const float t = std::max(kelvin, 0.f);
    return k * (t * t) * (t * t);
}

// Emitted radiance L_e(T) = blackbodyLuminance(T) x blackbodyColor(T).
inline Color blackbodyRadiance(float kelvin) { return blackbodyColor(kelvin) * blackbodyLuminance(kelvin); }

}  // namespace vdbmarch
