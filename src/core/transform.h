// Affine transforms (4x4, double precision, column vectors: p' = M p).
#pragma once

#include "core/math.h"

namespace vdbmarch {

struct Mat4 {
    double m[4][4];  // m[row][col]
    static Mat4 identity();
    static Mat4 translate(const Vec3& t);
    static Mat4 scale(const Vec3& s);
    // Rotation by angleDeg around axis (right-handed).
    static Mat4 rotate(const Vec3& axis, double angleDeg);
    Mat4 operator*(const Mat4& o) const;
    // Throws InputError (with `what` in the message) when singular.
    Mat4 inverse(const char* what = "transform") const;
    Mat4 transposed() const;
    double det3() const;  // determinant of the linear part
    // M (x, y, z, 1) and M (v, 0), computed in double, rounded to float.
    Vec3 point(double x, double y, double z) const {
        return Vec3(float(m[0][0] * x + m[0][1] * y + m[0][2] * z + m[0][3]),
                    float(m[1][0] * x + m[1][1] * y + m[1][2] * z + m[1][3]),
                    float(m[2][0] * x + m[2][1] * y + m[2][2] * z + m[2][3]));
    }
    Vec3 point(const Vec3& p) const { return point(p.x, p.y, p.z); }
    Vec3 vector(const Vec3& v) const {
        return Vec3(float(m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z),
                    float(m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z),
                    float(m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z));
    }
};

class Transform {
public:
    Transform() : mM(Mat4::identity()), mInv(Mat4::identity()) {}
    explicit Transform(const Mat4& m, const char* what = "transform") : mM(m), mInv(m.inverse(what)) {}
    Transform(const Mat4& m, const Mat4& inv) : mM(m), mInv(inv) {}

    Vec3 point(const Vec3& p) const { return mM.point(p); }
    Vec3 vector(const Vec3& v) const { return mM.vector(v); }
    // Normals transform with the inverse transpose.
    Vec3 normal(const Vec3& n) const {
        return Vec3(float(mInv.m[0][0] * n.x + mInv.m[1][0] * n.y + mInv.m[2][0] * n.z),
                    float(mInv.m[0][1] * n.x + mInv.m[1][1] * n.y + mInv.m[2][1] * n.z),
                    float(mInv.m[0][2] * n.x + mInv.m[1][2] * n.y + mInv.m[2][2] * n.z));
    }
    Transform inverse() const { return Transform(mInv, mM); }
    Transform operator*(const Transform& o) const { return Transform(mM * o.mM, o.mInv * mInv); }
    const Mat4& matrix() const { return mM; }
    const Mat4& inverseMatrix() const { return mInv; }
    bool isIdentity() const;

private:
    Mat4 mM, mInv;
};

}  // namespace vdbmarch
