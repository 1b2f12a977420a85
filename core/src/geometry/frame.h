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

// The unit vector along a direction the scene gives (not all zero, finite): glm::normalize
// where |v|² is a normal double, so every ordinary direction keeps its bits; otherwise (a
// component past 1e154, or all under 1e-154, whose square would overflow or underflow) v
// divided by its largest |component| first, which is exact in direction.
inline glm::dvec3 unit_direction(const glm::dvec3& v) {
  const double sq = glm::dot(v, v);
  if (sq >= std::numeric_limits<double>::min() && sq <= std::numeric_limits<double>::max())
    return glm::normalize(v);
  const double most = std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
  return most > 0 ? glm::normalize(v / most) : v;
}

struct PlaneFrame {
  glm::dvec3 n, u, v;
};

// nullopt when xdir has no part in the plane (parallel to the normal, to rounding).
inline std::optional<PlaneFrame> plane_frame(const glm::dvec3& normal, const glm::dvec3& xdir) {
  const glm::dvec3 n = unit_direction(normal);
  // xdir at a length of about 1 first (its scale does not change the frame), so that a tiny
  // or huge one is neither parallel by underflow nor infinite.
  const double most = std::max({std::abs(xdir.x), std::abs(xdir.y), std::abs(xdir.z)});
  const glm::dvec3 x = most > 0 && (most < 1e-150 || most > 1e150) ? xdir / most : xdir;
  const glm::dvec3 in_plane = x - glm::dot(x, n) * n;
  if (!(glm::length(in_plane) > 1e-12 * glm::length(x))) return std::nullopt;
  const glm::dvec3 u = unit_direction(in_plane);
  return PlaneFrame{n, u, glm::cross(n, u)};
}

}  // namespace rayfarm
