// The arithmetic of the course's reference program: a 32-bit x86 build whose every
// expression ran on the x87 unit with a 64-bit mantissa and was rounded to double when
// stored. Here each primitive computes in long double (that same 80-bit format on x86-64
// Linux) and rounds to double where the program stored; the images pin these rounding
// points (docs/profiles.md, "cpsc102 arithmetic").
#pragma once

#include <cmath>

namespace rayfarm::cpsc102 {

using X = long double;

inline double R(X x) { return static_cast<double>(x); }

struct V3 {
  double x = 0, y = 0, z = 0;
  double operator[](int i) const { return i == 0 ? x : i == 1 ? y : z; }
  double& operator[](int i) { return i == 0 ? x : i == 1 ? y : z; }
};

// Products and sum extended, one rounding.
inline double dot(const V3& a, const V3& b) {
  return R(static_cast<X>(a.x) * b.x + static_cast<X>(a.y) * b.y + static_cast<X>(a.z) * b.z);
}
// The root of the already rounded dot product.
inline double length(const V3& v) { return R(std::sqrt(static_cast<X>(dot(v, v)))); }
// Multiplied by a stored reciprocal of the length, component by component.
inline V3 unit(const V3& v) {
  const double s = R(1.0L / static_cast<X>(length(v)));
  return {R(static_cast<X>(v.x) * s), R(static_cast<X>(v.y) * s), R(static_cast<X>(v.z) * s)};
}
inline V3 add(const V3& a, const V3& b) {
  return {R(static_cast<X>(a.x) + b.x), R(static_cast<X>(a.y) + b.y), R(static_cast<X>(a.z) + b.z)};
}
inline V3 sub(const V3& a, const V3& b) {
  return {R(static_cast<X>(a.x) - b.x), R(static_cast<X>(a.y) - b.y), R(static_cast<X>(a.z) - b.z)};
}
inline V3 scale(const V3& a, double s) {
  return {R(static_cast<X>(a.x) * s), R(static_cast<X>(a.y) * s), R(static_cast<X>(a.z) * s)};
}
inline V3 mul(const V3& a, const V3& b) {
  return {R(static_cast<X>(a.x) * b.x), R(static_cast<X>(a.y) * b.y), R(static_cast<X>(a.z) * b.z)};
}
inline V3 cross(const V3& a, const V3& b) {
  return {R(static_cast<X>(a.y) * b.z - static_cast<X>(a.z) * b.y),
          R(static_cast<X>(a.z) * b.x - static_cast<X>(a.x) * b.z),
          R(static_cast<X>(a.x) * b.y - static_cast<X>(a.y) * b.x)};
}
// The point base + t·dir as the program computed a hit point.
inline V3 along(const V3& base, const V3& dir, double t) { return add(base, scale(dir, t)); }
// The unit normal of the plane through a triangle's vertices a, b, c, as the program found a
// 2009 `tri`'s plane: the unit cross product of its edges b - a and c - b. Not finite, or
// 0, where that product overflows or vanishes (the program then drew nothing).
inline V3 vertex_plane_normal(const V3& a, const V3& b, const V3& c) {
  return unit(cross(sub(b, a), sub(c, b)));
}

}  // namespace rayfarm::cpsc102
