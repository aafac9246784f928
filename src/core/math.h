// Small vector math for the renderer: float 3-vectors (positions, directions,
// RGB), with the handful of operations the integrators need. OpenVDB's math is
// kept out of this header so most translation units stay light.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace vdbmarch {

constexpr float Pi = 3.14159265358979323846f;
constexpr double PiD = 3.14159265358979323846;
constexpr float InvPi = 0.31830988618379067154f;
constexpr float Inv4Pi = 0.07957747154594766788f;
constexpr float Infinity = std::numeric_limits<float>::infinity();

struct Vec3 {
    float x = 0, y = 0, z = 0;
    constexpr Vec3() = default;
    constexpr Vec3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
    constexpr explicit Vec3(float s) : x(s), y(s), z(s) {}
    float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
    Vec3 operator-() const { return {-x, -y, -z}; }
    Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
    Vec3& operator-=(const Vec3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
    Vec3& operator*=(const Vec3& o) { x *= o.x; y *= o.y; z *= o.z; return *this; }
    Vec3& operator*=(float s) { x *= s; y *= s; z *= s; return *this; }
    Vec3& operator/=(float s) { float r = 1.f / s; x *= r; y *= r; z *= r; return *this; }
};

// RGB radiance, coefficients and throughput share the vector type.
using Color = Vec3;

inline Vec3 operator+(Vec3 a, const Vec3& b) { return a += b; }
inline Vec3 operator-(Vec3 a, const Vec3& b) { return a -= b; }
inline Vec3 operator*(Vec3 a, const Vec3& b) { return a *= b; }
inline Vec3 operator*(Vec3 a, float s) { return a *= s; }
inline Vec3 operator*(float s, Vec3 a) { return a *= s; }
inline Vec3 operator/(Vec3 a, float s) { return a /= s; }
inline Vec3 operator/(const Vec3& a, const Vec3& b) { return {a.x / b.x, a.y / b.y, a.z / b.z}; }
inline bool operator==(const Vec3& a, const Vec3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }
inline bool operator!=(const Vec3& a, const Vec3& b) { return !(a == b); }

inline float dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float lengthSquared(const Vec3& v) { return dot(v, v); }
inline float length(const Vec3& v) { return std::sqrt(dot(v, v)); }
inline Vec3 normalize(const Vec3& v) { return v / length(v); }
inline Vec3 min(const Vec3& a, const Vec3& b) { return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)}; }
inline Vec3 max(const Vec3& a, const Vec3& b) { return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}; }
inline Vec3 exp(const Vec3& v) { return {std::exp(v.x), std::exp(v.y), std::exp(v.z)}; }
inline float maxComponent(const Vec3& v) { return std::max(v.x, std::max(v.y, v.z)); }
inline float minComponent(const Vec3& v) { return std::min(v.x, std::min(v.y, v.z)); }
inline float average(const Vec3& v) { return (v.x + v.y + v.z) * (1.f / 3.f); }
inline bool isBlack(const Vec3& v) { return v.x == 0 && v.y == 0 && v.z == 0; }
inline bool isFinite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
inline float luminance(const Color& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

template <typename T>
inline T clamp(T v, T lo, T hi) { return v < lo ? lo : (v > hi ? hi : v); }
inline float safeSqrt(float v) { return std::sqrt(std::max(0.f, v)); }
inline float radians(float deg) { return deg * (Pi / 180.f); }
// 1 - cos of the angle between w and a unit axis, accurate for tiny angles
// and for w a rounding away from unit length.
inline float oneMinusCosTo(const Vec3& w, const Vec3& axis) {
    float len = length(w), c = dot(w, axis) / len;
    if (c <= 0) return 1 - c;
    return lengthSquared(cross(w, axis)) / (len * len) / (1 + c);
}

// Orthonormal basis around a unit vector (Duff et al. 2017, branchless).
inline void coordinateSystem(const Vec3& n, Vec3& s, Vec3& t) {
    float sign = std::copysign(1.f, n.z);
    float a = -1.f / (sign + n.z);
    float b = n.x * n.y * a;
    s = Vec3(1.f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    t = Vec3(b, sign + n.y * n.y * a, -n.y);
}

struct Ray {
    Vec3 o, d;  // d is unit length everywhere in the renderer
    Vec3 at(float t) const { return o + d * t; }
    // In double precision: exact lattice positions even when t is large.
    Vec3 at(double t) const {
        return Vec3(float(double(o.x) + double(d.x) * t), float(double(o.y) + double(d.y) * t),
                    float(double(o.z) + double(d.z) * t));
    }
};

struct BBox {
    Vec3 lo{Infinity, Infinity, Infinity};
    Vec3 hi{-Infinity, -Infinity, -Infinity};
    bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
    // False for an unbounded box (infinite fog) and for the empty box.
    bool isFinite() const { return vdbmarch::isFinite(lo) && vdbmarch::isFinite(hi); }
    void expand(const Vec3& p) { lo = min(lo, p); hi = max(hi, p); }
    void expand(const BBox& b) { lo = min(lo, b.lo); hi = max(hi, b.hi); }
    Vec3 center() const { return (lo + hi) * 0.5f; }
    Vec3 extent() const { return hi - lo; }
    bool contains(const Vec3& p) const {
        return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
    }
    // Slab test; returns the parametric overlap of the ray with the box
    // clipped to [t0, t1].
    bool intersect(const Ray& r, float& t0, float& t1) const {
        for (int a = 0; a < 3; ++a) {
            float inv = 1.f / r.d[a];
            float tn = (lo[a] - r.o[a]) * inv, tf = (hi[a] - r.o[a]) * inv;
            if (tn > tf) std::swap(tn, tf);
            // NaN from 0 * inf (ray in the slab plane) must not clip.
            if (!(tn <= t0)) t0 = std::isnan(tn) ? t0 : tn;
            if (!(tf >= t1)) t1 = std::isnan(tf) ? t1 : tf;
            if (t0 > t1) return false;
        }
        return true;
    }
};

// A parametric interval along a ray.
struct Interval {
    float t0, t1;
};

}  // namespace vdbmarch
