// The scene as the course's reference program held it after loading: objects and lights in
// file order, unit normals and plane frames computed with its arithmetic (x87.h).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "accel/bvh.h"
#include "rayfarm/options.h"
#include "rayfarm/scene.h"
#include "render/cpsc102/x87.h"

namespace rayfarm::cpsc102 {

struct RefMaterial {
  V3 ambient, diffuse, specular;
  double shininess = 0;  // 0: no glint
  double transparency = 0;
  V3 filter;  // transparency · diffuse / max(diffuse): what it lets through
  bool reflects = false;
};

// A plane's frame: rows u, n × u, n (the .log files print it as the rotation matrix).
struct Frame {
  V3 row0, row1, normal;
};

struct RefTexture {
  const Image* image = nullptr;
};

struct RefObject {
  enum Kind { sphere, plane, fplane, tiled, texplane, triangle, revsurf } kind = sphere;
  int material = 0;
  int alt_material = 0;  // tiled
  // sphere
  V3 center;
  double radius = 0;
  // plane kinds and triangles
  V3 normal, point;
  double n_dot_point = 0;
  Frame frame;
  double width = 0, height = 0;
  bool world_xz = false;  // the 2009 tiled plane
  const Image* texture = nullptr;
  int mode = 0;
  // triangle: the vertices in the plane's frame (x, y), relative to `point`
  double tx[3] = {}, ty[3] = {};
  // revsurf
  int surfer = 1;
  V3 base, axis;
  double rev_height = 0;
};

struct RefLight {
  LightKind kind = LightKind::point;
  V3 location, emissivity;
  V3 direction;      // spot: unit(point − location)
  double cos_theta;  // spot
  // projector: the slide
  V3 normal, point;
  double n_dot_point = 0;
  Frame frame;
  double width = 0, height = 0;
  const Image* texture = nullptr;
};

struct RefScene {
  int width = 0, height = 0;
  double world_width = 0, world_height = 0;
  // A texel of a mode-1 texplane is a pixel of the camera's own size, whatever is rendered.
  double texel_width = 0, texel_height = 0;
  V3 eye;
  V3 background;
  double max_dist = 20;
  int max_depth = 64;
  int spp = 1;
  std::uint32_t seed = 1;  // of the jitter stream (glibc's srandom; 0 is taken as 1, as glibc does)
  bool shadows = true;
  std::vector<RefMaterial> materials;
  std::vector<RefObject> objects;
  std::vector<RefLight> lights;
  // With many objects: the bounded ones in a hierarchy (whose answers are the loop's), the
  // rest (planes, and spheres too small for its margin) tested every time. Empty: a loop.
  Bvh bvh;
  std::vector<std::int32_t> always;
};

// Below this many objects the loop is as fast.
inline constexpr std::size_t kReferenceBvhMin = 8;

// Builds the reference program's view of `scene`; textures must be resolved. Returns an
// error message for what it cannot render.
RefScene prepare_reference(const Scene& scene, const RenderOptions& options, int camera);

// Puts the bounded objects behind a hierarchy (prepare_reference does when it pays).
void build_reference_bvh(RefScene& scene);

}  // namespace rayfarm::cpsc102
