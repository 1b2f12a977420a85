// A plane's frame in double precision: u is xdir's part in the plane (the window's x axis),
// v = n × u, n the unit normal. Scene-level code (preparation of the lecture profile, the
// POV-Ray export) shares it; the cpsc102 profile computes its own in the course program's
// arithmetic (render/cpsc102/reference_scene.cpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace rayfarm {

// A direction the scene gives (finite), at a length where its square is a normal double: v
// itself when |v|² already is, so every ordinary direction keeps its bits; otherwise (a
// component past 1e154, or all under 1e-154) v divided by its largest |component|, which is
// exact in direction. Any type with doubles x, y, z (the cpsc102 profile's V3 too).
template <class V>
V at_unit_scale(const V& v) {
  const double sq = (v.x * v.x + v.y * v.y) + v.z * v.z;
  if (sq >= std::numeric_limits<double>::min() && sq <= std::numeric_limits<double>::max()) return v;
  const double most = std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
  return most > 0 ? V{v.x / most, v.y / most, v.z / most} : v;
}

// The unit vector along a direction the scene gives (not all zero, finite).
inline glm::dvec3 unit_direction(const glm::dvec3& v) {
  const glm::dvec3 scaled = at_unit_scale(v);
  return scaled == glm::dvec3(0) ? v : glm::normalize(scaled);
}

struct PlaneFrame {
  glm::dvec3 n, u, v;
};

// nullopt when xdir has no part in the plane (parallel to the normal, to rounding).
inline std::optional<PlaneFrame> plane_frame(const glm::dvec3& normal, const glm::dvec3& xdir) {
  const glm::dvec3 n = unit_direction(normal);
  // Its scale does not change the frame: a tiny or huge xdir is then neither parallel by
  // underflow nor infinite.
  const glm::dvec3 x = at_unit_scale(xdir);
  const glm::dvec3 in_plane = x - glm::dot(x, n) * n;
  if (!(glm::length(in_plane) > 1e-12 * glm::length(x))) return std::nullopt;
  const glm::dvec3 u = unit_direction(in_plane);
  return PlaneFrame{n, u, glm::cross(n, u)};
}

}  // namespace rayfarm
