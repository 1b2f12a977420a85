// What a tracer met along one sample's path: written by the tracers built to record
// (kRecord, explain.cpp); a render's tracers have no recording code at all. Objects are
// numbered as the tracer numbers them; explain.cpp maps them to the scene's file order.
#pragma once

#include <array>
#include <vector>

namespace rayfarm {

struct RecordedLight {
  enum Status : unsigned char {
    lit,
    filtered,
    shadowed,
    faces_away,
    outside_cone,
    off_slide,
    at_point
  };
  int light = -1;
  Status status = lit;
  int blocker = -1;  // shadowed: the object in the way; filtered: the first filter
  double distance = 0;
  double n_dot_l = 0;
  std::array<double, 3> emissivity{};           // as it reaches the point
  std::array<double, 3> diffuse{}, specular{};  // the terms added
  double highlight_base = 0;                    // R·V, or N·H: what is raised to the shininess
  double diffuse_distance = 0;                  // cpsc102: what the diffuse term was divided by
};

struct RecordedHit {
  enum class Ray : unsigned char { primary, reflected, transmitted };
  Ray ray = Ray::primary;
  int parent = -1;
  int depth = 0;
  std::array<double, 3> origin{}, direction{};
  int object = -1;
  bool capped = false;  // no object within max_dist, or the path already beyond it
  double t = 0, travelled = 0;
  std::array<double, 3> point{}, normal{}, ambient{}, diffuse_colour{};
  std::array<double, 3> specular{};      // the material's
  double shininess = 0;                  // as the profile uses it (cpsc102: 0, no highlight)
  int first_light = 0, light_count = 0;  // its entries in Recorder::lights
  std::array<double, 3> local{}, value{};
  // What the children add: reflection `weight`; transmission keep · local + filter · value.
  std::array<double, 3> weight{}, filter{};
  double keep = 1;
  int reflected = -1, transmitted = -1;
};

struct Recorder {
  // Whether to name the object that shadows a light (a search of its own in the lecture
  // profile); the per-pixel records need only the light's status.
  bool blockers = true;
  std::array<double, 3> screen_point{};
  std::vector<RecordedHit> hits;
  std::vector<RecordedLight> lights;

  void clear() {
    hits.clear();
    lights.clear();
  }
  // A new hit for a ray leaving hit `parent` (-1: the primary ray) as `ray`; its index.
  int begin(RecordedHit::Ray ray, int parent, int depth) {
    RecordedHit& h = hits.emplace_back();
    h.ray = ray;
    h.parent = parent;
    h.depth = depth;
    h.first_light = static_cast<int>(lights.size());
    return static_cast<int>(hits.size()) - 1;
  }
  RecordedLight& light(int hit, int index) {
    ++hits[hit].light_count;
    RecordedLight& l = lights.emplace_back();
    l.light = index;
    return l;
  }
};

template <class V>
std::array<double, 3> triple(const V& v) {
  return {static_cast<double>(v[0]), static_cast<double>(v[1]), static_cast<double>(v[2])};
}

}  // namespace rayfarm
