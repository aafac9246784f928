// The light arriving from infinitely far away: a constant background colour
// or a lat-long environment map (an HDR sky). Used by every estimator: paths
// and camera rays that escape read radiance(), next-event estimation samples
// the map by sample() / pdf(), photons are emitted from it
// (photons/photon_emission.h).
//
// Orientation (Mitsuba 3's and pbrt-v3's lat-long convention, +Y up): the
// top row of the image looks straight up (+Y), the middle row is the
// horizon, the bottom row looks down; column u in [0, 1) is the azimuth
// phi = 2 pi u measured from -Z towards +X, so the image's centre column
// looks along +Z and its left edge along -Z. A direction is
//   (sin(theta) sin(phi), cos(theta), -sin(theta) cos(phi)),  theta = pi v.
// `rotation` turns the map about +Y by that many degrees (counter-clockwise
// seen from above).
#pragma once

#include <string>
#include <vector>

#include "core/distribution.h"
#include "core/math.h"
#include "parse/scene_desc.h"

namespace vdbmarch {

class Environment {
public:
    // Black: nothing arrives from far away.
    Environment() = default;
    // The same radiance from every direction.
    explicit Environment(const Color& constant) : mConstant(constant) {}
    // Reads and validates desc.file (an EXR with a 2:1 aspect); `what` names
    // it in messages. Texels that are NaN, infinite or negative become 0,
    // with one warning that counts them.
    explicit Environment(const EnvironmentDesc& desc, const std::string& what);
    // A map from texels (width x height RGB, top row first), for tests.
    Environment(std::vector<Color> texels, int width, int height, float scale, float rotationDeg);

    bool hasMap() const { return mWidth > 0; }
    bool isBlack() const { return hasMap() ? !(mIntegralAvg > 0) : vdbmarch::isBlack(mConstant); }

    // Radiance arriving along -w, i.e. seen looking in direction w (unit):
    // constant over each texel, the function the light sampling below has
    // its pdf for.
    Color radiance(const Vec3& w) const;
    // The map as a backdrop, where a camera path that has not scattered
    // sees it (no MIS involved): bilinear between texel centres, so a sky
    // gradient does not show its texel rows.
    Color radianceSeen(const Vec3& w) const;
    // A direction w by the map's texel power (radiance x solid angle), its
    // solid-angle pdf, and radiance(w) / pdf. False (pdf 0) if none.
    bool sample(float u1, float u2, Vec3& w, float& pdf, Color& radianceOverPdf) const;
    // Solid-angle density of sample() at w.
    float pdf(const Vec3& w) const;
    // The integral of radiance over the sphere (W / m^2 / sr x sr): 4 pi
    // times the mean radiance; photon emission shares its budget by it.
    Color integral() const;

    int width() const { return mWidth; }
    int height() const { return mHeight; }

    // The map's (u, v) of a direction and back (documented above; no rotation).
    static void directionToUv(const Vec3& local, float& u, float& v);
    static Vec3 uvToDirection(float u, float v);

private:
    void build(std::vector<Color> texels, int width, int height, float scale, float rotationDeg);
    Vec3 toLocal(const Vec3& w) const { return {mCos * w.x - mSin * w.z, w.y, mSin * w.x + mCos * w.z}; }
    Vec3 toWorld(const Vec3& l) const { return {mCos * l.x + mSin * l.z, l.y, -mSin * l.x + mCos * l.z}; }
    const Color& texel(float u, float v) const;

    Color mConstant{0, 0, 0};
    int mWidth = 0, mHeight = 0;
    std::vector<Color> mTexels;  // scaled
    PiecewiseConstant2D mDistribution;
    Color mIntegral{0, 0, 0};
    float mIntegralAvg = 0;
    float mCos = 1, mSin = 0;  // rotation about +Y
};

}  // namespace vdbmarch
