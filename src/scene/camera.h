#pragma once

#include "core/math.h"
#include "parse/scene_desc.h"

namespace vdbmarch {

// Pinhole perspective or orthographic camera. Pixel coordinates are
// continuous: (0,0) is the top-left corner of the image, (w,h) bottom-right.
class Camera {
public:
    explicit Camera(const CameraDesc& d);
    Ray generateRay(float px, float py) const;
    int width() const { return mWidth; }
    int height() const { return mHeight; }
    // Camera-space depth of p: its distance along the view axis (Cycles' Z pass).
    float viewDepth(const Vec3& p) const { return dot(p - mPos, mForward); }

private:
    bool mOrtho;
    Vec3 mPos, mForward, mRight, mUp;
    float mHalfW, mHalfH;  // half extents of the image plane at distance 1 (or world units)
    int mWidth, mHeight;
};

}  // namespace vdbmarch
