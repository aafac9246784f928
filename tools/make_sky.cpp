// Writes the bundled procedural sky, vdb_samples/sky.exr: a lat-long map
// (src/scene/environment.h has the orientation) of a clear afternoon sky. It
// is a look, not a physical sky model: a blue zenith fading to a pale
// horizon, a warm glow around the sun, a dark ground below the horizon, and
// a sun disc whose texels are scaled so the disc's irradiance at normal
// incidence is exactly `sunIrradiance` (the same as a directional light of
// that irradiance pointing along -sunDir).
// Usage: make_sky OUT.exr [WIDTH]   (height = WIDTH / 2; default 512)
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "image/exr_io.h"
#include "scene/environment.h"

using namespace vdbmarch;

namespace {


Color mix(const Color& a, const Color& b, float t) { return a * (1 - t) + b * t; }

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: make_sky OUT.exr [WIDTH]\n");
        return 2;
    }
    const int width = argc > 2 ? std::atoi(argv[2]) : 512, height = width / 2;
    if (width < 8 || width % 2) {
        std::fprintf(stderr, "make_sky: WIDTH must be even and >= 8\n");
        return 2;
    }
    // The sun: 35 degrees up, behind the right shoulder of the sample
    // cloud's camera (the reverse of cloud.json's light direction).
    const Vec3 sunDir = normalize(Vec3(-0.55f, 0.75f, 0.35f));
    const Color sunIrradiance(5.4f, 5.0f, 4.3f);
    const double sunRadius = 2.0 * PiD / 180;  // wider than the real 0.27 deg: a few texels at 512 wide
    const Color zenith(0.10f, 0.22f, 0.60f), horizon(0.55f, 0.65f, 0.80f), ground(0.08f, 0.075f, 0.07f);
    const Color glow(0.9f, 0.75f, 0.5f);

    Image img(width, height);
    double sunSolidAngle = 0;
    std::vector<bool> isSun(size_t(width) * size_t(height), false);
    for (int y = 0; y < height; ++y) {
        const double t0 = PiD * y / height, t1 = PiD * (y + 1) / height;
        const double dOmega = 2 * PiD / width * (std::cos(t0) - std::cos(t1));
        for (int x = 0; x < width; ++x) {
            const Vec3 d = Environment::uvToDirection((x + 0.5f) / width, (y + 0.5f) / height);
            const double angle = std::acos(std::min(1.0, std::max(-1.0, double(dot(d, sunDir)))));
            Color c;
            if (d.y >= 0) {
                c = mix(horizon, zenith, std::pow(d.y, 0.45f));
                // Forward scattering haze around the sun, stronger near the horizon.
                c += glow * float(0.6 * std::exp(-angle / 0.25) + 0.15 * std::exp(-angle / 1.0) * (1 - d.y));
            } else {
                c = mix(horizon * 0.4f, ground, std::min(1.f, -d.y * 8));
            }
            if (angle < sunRadius) {
                isSun[size_t(y) * size_t(width) + size_t(x)] = true;
                sunSolidAngle += dOmega;
            }
            img.set(x, y, c, 1);
        }
    }
    // Sun texels: radiance so that their solid angle x radiance = E.
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            if (isSun[size_t(y) * size_t(width) + size_t(x)])
                img.set(x, y, img.rgb(x, y) + sunIrradiance / float(sunSolidAngle), 1);
    writeExr(argv[1], img,
             {{"vdbmarch:generator", "tools/make_sky.cpp"},
              {"vdbmarch:sun", "direction towards the sun (-0.55, 0.75, 0.35) normalised; disc irradiance (5.4, 5.0, 4.3)"}});
    std::printf("make_sky: wrote %s (%dx%d, sun disc %.3g sr)\n", argv[1], width, height, sunSolidAngle);
    return 0;
}
