// The render-ready scene in the tracer's precision: flat arrays, unit normals, the chosen
// camera, and the list of pipeline parts this scene and these options need.
#pragma once

#include <string>
#include <vector>

#include "rayfarm/intersect.h"
#include "rayfarm/options.h"
#include "rayfarm/scene.h"

namespace rayfarm {

// Which parts of the pipeline a render runs; everything off costs nothing.
struct Features {
  bool reflection = true;  // some visible material reflects and max_depth > 0
  bool highlight = true;   // some material has a specular highlight and there are lights
  bool shadows = true;     // shadow rays: option on, lights and objects present
  bool lights = true;      // any light contributes at all
  bool supersampling = false;

  std::vector<std::string> parts() const;
};

template <class T>
struct PreparedMaterial {
  Vec3<T> ambient, diffuse, specular;
  T shininess;
  T max_specular;  // largest specular channel: the weight of its reflection
  bool reflects;
  bool highlights;
};

template <class T>
struct PreparedSphere {
  Vec3<T> centre;
  T radius;
  int material;
};

template <class T>
struct PreparedPlane {
  Vec3<T> normal;  // unit
  Vec3<T> point;
  int material;
};

template <class T>
struct PreparedLight {
  Vec3<T> location;
  Vec3<T> emissivity;
};

template <class T>
struct PreparedScene {
  int width = 0;
  int height = 0;
  Vec3<T> eye{0};
  T world_width = 0;
  T world_height = 0;
  Vec3<T> background{0};
  T max_dist = 0;
  T bailout = 0;
  int max_depth = 0;
  bool blinn = false;
  int spp = 1;
  std::uint64_t seed = 0;

  std::vector<PreparedMaterial<T>> materials;
  std::vector<PreparedSphere<T>> spheres;
  std::vector<PreparedPlane<T>> planes;
  std::vector<PreparedLight<T>> lights;
  Features features;
};

// Converts a checked scene for rendering. `camera` is an index into scene.cameras.
template <class T>
PreparedScene<T> prepare_scene(const Scene& scene, const RenderOptions& options, int camera);

}  // namespace rayfarm
