// Ray/sphere and ray/plane intersection, templated on the tracer's precision.
#pragma once

#include <cmath>
#include <optional>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace rayfarm {

template <class T>
using Vec3 = glm::vec<3, T, glm::defaultp>;

template <class T>
struct Roots {
  T near;  // near <= far
  T far;
};

// Both roots of |o + t d - c| = r for a unit direction d, in the cancellation-free form of
// Ray Tracing Gems ch. 7: the discriminant as r^2 - |f - (f.d) d|^2 (no difference of two
// large squares), the larger-magnitude root q = -(b + sign(b) sqrt(D)), the other as c/q.
template <class T>
[[gnu::always_inline]] inline std::optional<Roots<T>> sphere_roots(const Vec3<T>& o,
                                                                   const Vec3<T>& d,
                                                                   const Vec3<T>& centre,
                                                                   T radius) {
  Vec3<T> f = o - centre;
  T b = glm::dot(f, d);
  Vec3<T> l = f - b * d;
  T disc = radius * radius - glm::dot(l, l);
  if (!(disc >= 0)) return std::nullopt;
  T c = glm::dot(f, f) - radius * radius;
  T s = std::sqrt(disc);
  T q = b >= 0 ? -(b + s) : -(b - s);
  if (q == 0) return Roots<T>{0, 0};
  T t0 = c / q;
  T t1 = q;
  return t0 <= t1 ? Roots<T>{t0, t1} : Roots<T>{t1, t0};
}

// The textbook form of the lecture notes (A t^2 + B t + C, t = (-B -+ sqrt(B^2 - 4AC)) / 2A).
// Kept to show its failure in reports and tests; never used for rendering.
template <class T>
std::optional<Roots<T>> sphere_roots_naive(const Vec3<T>& o, const Vec3<T>& d,
                                           const Vec3<T>& centre, T radius) {
  Vec3<T> pc = o - centre;
  T a = glm::dot(d, d);
  T b = 2 * glm::dot(pc, d);
  T c = glm::dot(pc, pc) - radius * radius;
  T disc = b * b - 4 * a * c;
  if (!(disc > 0)) return std::nullopt;  // the lecture's test: B^2 - 4AC > 0
  T s = std::sqrt(disc);
  return Roots<T>{(-b - s) / (2 * a), (-b + s) / (2 * a)};
}

// Distance along a unit-or-not direction d to the plane through `point` with normal n;
// nullopt when the ray is parallel to the plane.
template <class T>
std::optional<T> plane_distance(const Vec3<T>& o, const Vec3<T>& d, const Vec3<T>& n,
                                const Vec3<T>& point) {
  T denom = glm::dot(n, d);
  if (denom == 0) return std::nullopt;
  T t = glm::dot(n, point - o) / denom;
  if (!std::isfinite(t)) return std::nullopt;
  return t;
}

// plane_distance when it is finite and > 0, else -1; the same t, but a plane behind the ray
// (numerator and denominator of opposite signs: most shadow and reflected rays off a floor)
// costs no division, the slowest step of the test. `num` (optional) gets n · (point − o).
template <class T>
T plane_distance_ahead(const Vec3<T>& o, const Vec3<T>& d, const Vec3<T>& n, const Vec3<T>& point,
                       T* num_out = nullptr) {
  const T denom = glm::dot(n, d);
  const T num = glm::dot(n, point - o);
  if (num_out) *num_out = num;
  // A quotient > 0 needs both > 0 or both < 0; a zero or NaN fails both.
  if (!(num > 0 ? denom > 0 : num < 0 && denom < 0)) return T(-1);
  const T t = num / denom;
  return std::isfinite(t) && t > 0 ? t : T(-1);
}

}  // namespace rayfarm
