#include "scene/camera.h"

#include <cmath>

namespace vdbmarch {

Camera::Camera(const CameraDesc& d)
    : mOrtho(d.type == CameraDesc::Type::Orthographic), mPos(d.position), mWidth(d.width), mHeight(d.height) {
    mForward = normalize(d.lookAt - d.position);
    mRight = normalize(cross(mForward, d.up));
    mUp = cross(mRight, mForward);
    float aspect = float(d.width) / float(d.height);
    if (mOrtho) {
        mHalfW = 0.5f * d.widthWorld;
        mHalfH = mHalfW / aspect;
    } else {
        mHalfH = std::tan(radians(d.fovDeg) * 0.5f);
        mHalfW = mHalfH * aspect;
    }
}

Ray Camera::generateRay(float px, float py) const {
    float sx = (2.f * px / float(mWidth) - 1.f) * mHalfW;
    float sy = (1.f - 2.f * py / float(mHeight)) * mHalfH;
    if (mOrtho) return {mPos + mRight * sx + mUp * sy, mForward};
    return {mPos, normalize(mForward + mRight * sx + mUp * sy)};
}

}  // namespace vdbmarch
