// Tracing through a smooth glass sphere in double precision, shared by the
// connection solver (sphere_connections.cpp) and the folds of its caustics
// (sphere_folds.cpp): the roots and the central differences of the
// spreading need more digits than float keeps.
#pragma once

#include <cmath>

#include "scene/scene.h"

namespace vdbmarch::sphere_trace {

// Double-precision vectors: the roots and the spreading's central
// differences need more digits than float keeps.
struct D3 {
    double x = 0, y = 0, z = 0;
    D3() = default;
    D3(double a, double b, double c) : x(a), y(b), z(c) {}
    explicit D3(const Vec3& v) : x(v.x), y(v.y), z(v.z) {}
    D3 operator+(const D3& o) const { return {x + o.x, y + o.y, z + o.z}; }
    D3 operator-(const D3& o) const { return {x - o.x, y - o.y, z - o.z}; }
    D3 operator*(double s) const { return {x * s, y * s, z * s}; }
    Vec3 f() const { return Vec3(float(x), float(y), float(z)); }
};
inline double dot(const D3& a, const D3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline D3 cross(const D3& a, const D3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline double length(const D3& a) { return std::sqrt(dot(a, a)); }
inline D3 normalize(const D3& a) { return a * (1 / length(a)); }


struct Traced {
    D3 p1, p2, wo;
    double transmission = 0;
};

// Refraction of unit d at unit normal n facing the arriving ray, eta =
// n_transmitted / n_incident; F the Fresnel reflectance. False on total
// internal reflection.
bool refract(const D3& d, const D3& n, double eta, D3& t, double& F);
// The ray x + t w into sphere s and out again.
bool trace(const GlassSphere& s, const D3& x, const D3& w, Traced& out);
// The ray x + t w across the surface of sphere s once: into it from
// outside, or out of it from inside.
bool traceAcross(const GlassSphere& s, const D3& x, const D3& w, Traced& out);

}  // namespace vdbmarch::sphere_trace
