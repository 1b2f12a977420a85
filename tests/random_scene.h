// Seeded random scenes for the tests that hold an acceleration structure to the plain loop:
// spheres over three decades of radius, with exact duplicates and touching pairs.
#pragma once

#include <cmath>
#include <glm/geometric.hpp>
#include <random>
#include <string>

#include <glm/geometric.hpp>

#include "rayfarm/scene.h"

namespace rayfarm::test {

struct Rng {
  std::mt19937_64 engine;
  explicit Rng(std::uint64_t seed) : engine(seed) {}
  double in(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(engine); }
  int below(int n) { return std::uniform_int_distribution<int>(0, n - 1)(engine); }
  bool chance(double p) { return in(0, 1) < p; }
  glm::dvec3 point(double extent) {
    return {in(-extent, extent), in(-extent, extent), in(-extent, extent)};
  }
  glm::dvec3 direction() {
    for (;;) {
      glm::dvec3 v = point(1);
      double l = glm::length(v);
      if (l > 0.1 && l <= 1) return v / l;
    }
  }
};

inline Scene base_scene() {
  Scene s;
  Camera cam;
  cam.name = "c";
  cam.width = 8;
  cam.height = 6;
  cam.world_width = 8;
  cam.world_height = 6;
  cam.viewpoint = {4, 3, 5};
  s.cameras.push_back(cam);
  Material m;
  m.name = "m";
  m.diffuse = glm::dvec3(0.5);
  s.materials.push_back(m);
  Light light;
  light.name = "l";
  light.location = {0, 10, 0};
  s.lights.push_back(light);
  return s;
}

inline void add_sphere(Scene& s, glm::dvec3 centre, double radius) {
  Object& o = s.objects.emplace_back();
  o.name = "s" + std::to_string(s.objects.size() - 1);
  o.kind = EntityKind::sphere;
  o.shape = Sphere{centre, radius};
}

// The i-th object, a sphere (random scenes have the spheres first).
inline const Sphere& sphere_at(const Scene& s, size_t i) { return *s.objects[i].as<Sphere>(); }

// `count` spheres in a cube of side 2 * extent, radii over three decades, with a share of
// exact duplicates and of spheres touching an earlier one.
inline Scene random_scene(Rng& rng, int count, double extent) {
  Scene s = base_scene();
  for (int i = 0; i < count; ++i) {
    if (i > 0 && rng.chance(0.1)) {  // coincident with an earlier sphere
      const Sphere& twin = sphere_at(s, rng.below(i));
      add_sphere(s, twin.center, twin.radius);
    } else if (i > 0 && rng.chance(0.1)) {  // touching an earlier sphere from outside
      const Sphere& other = sphere_at(s, rng.below(i));
      double r = extent * std::exp(rng.in(std::log(1e-3), std::log(0.1)));
      add_sphere(s, other.center + (other.radius + r) * rng.direction(), r);
    } else {
      add_sphere(s, rng.point(extent), extent * std::exp(rng.in(std::log(1e-3), std::log(0.1))));
    }
  }
  Object& floor = s.objects.emplace_back();
  floor.kind = EntityKind::plane;
  floor.shape = Plane{{0, 1, 0}, {0, -extent, 0}};
  return s;
}

}  // namespace rayfarm::test
