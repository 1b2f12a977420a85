// A plane's frame in double precision: u is xdir's part in the plane (the window's x axis),
// v = n × u, n the unit normal. Scene-level code (preparation of the lecture profile, the
// POV-Ray export) shares it; the cpsc102 profile computes its own in the course program's
// arithmetic (render/cpsc102/reference_scene.cpp).
#pragma once

#include <optional>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace rayfarm {

struct PlaneFrame {
  glm::dvec3 n, u, v;
};

// nullopt when xdir has no part in the plane (parallel to the normal, to rounding).
inline std::optional<PlaneFrame> plane_frame(const glm::dvec3& normal, const glm::dvec3& xdir) {
  const glm::dvec3 n = glm::normalize(normal);
  const glm::dvec3 in_plane = xdir - glm::dot(xdir, n) * n;
  if (!(glm::length(in_plane) > 1e-12 * glm::length(xdir))) return std::nullopt;
  const glm::dvec3 u = glm::normalize(in_plane);
  return PlaneFrame{n, u, glm::cross(n, u)};
}

}  // namespace rayfarm
