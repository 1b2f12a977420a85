// The render-ready scene in the tracer's precision: flat arrays, unit normals, the chosen
// camera, and the list of pipeline parts this scene and these options need.
#pragma once

#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "accel/bvh.h"
#include "accel/light_buffer.h"
#include "accel/mirror_bins.h"
#include "accel/screen_bins.h"
#include "rayfarm/intersect.h"
#include "rayfarm/options.h"
#include "rayfarm/scene.h"
#include "render/shapes.h"
#include "render/tile_grid.h"

namespace rayfarm {

// Which parts of the pipeline a render runs; everything off costs nothing.
struct Features {
  bool reflection = true;  // some visible material reflects and max_depth > 0
  bool highlight = true;   // some material has a specular highlight and there are lights
  bool shadows = true;     // shadow rays: option on, lights and objects present
  bool lights = true;      // any light contributes at all
  bool transparency = false;  // some material lets light through: rays and shadows go on
  bool supersampling = false;
  bool bvh = false;  // spheres behind a hierarchy instead of a loop
  bool screen_bins = false;    // primary rays find their sphere by projection (screen_bins.h)
  bool light_buffers = false;  // shadow rays test the spheres of one direction cell (light_buffer.h)
  bool mirror_bins = false;  // reflection rays off planes from primary hits use mirror_bins.h
  // One sample a pixel: a path stops once its pixel's byte is settled (Tracer::byte_settled).
  bool byte_cutoff = false;

  std::vector<std::string> parts() const;
};

template <class T>
struct PreparedMaterial {
  Vec3<T> ambient, diffuse, specular;
  T shininess;
  T max_specular;  // largest specular channel: the weight of its reflection
  bool reflects;
  bool highlights;
  bool lit = true;  // lights can add anything: some diffuse, or a highlight
  T transparency = 0;
  Vec3<T> filter{0};  // transparency · diffuse / max(diffuse): what it lets through
  // For highlight_negligible (tracer.h), set by bound_highlight: whether specular ·
  // pow(base, shininess) is bounded there (shininess > 0 and finite, every specular channel
  // finite), and per channel the power of two E with |specular| < 2^E (kZeroSpecular for a
  // channel of 0).
  bool highlight_bounded = false;
  std::array<int, 3> specular_exp{};
  static constexpr int kZeroSpecular = std::numeric_limits<int>::min();
};

// Sets m's highlight_bounded and specular_exp from its specular and shininess.
template <class T>
void bound_highlight(PreparedMaterial<T>& m) {
  m.highlight_bounded = m.shininess > 0 && std::isfinite(m.shininess);
  for (int c = 0; c < 3; ++c) {
    m.highlight_bounded = m.highlight_bounded && std::isfinite(m.specular[c]);
    int e = 0;
    std::frexp(m.specular[c], &e);  // |specular| = f 2^e, 1/2 <= f < 1
    m.specular_exp[c] = m.specular[c] == 0 ? PreparedMaterial<T>::kZeroSpecular : e;
  }
}

// Four coordinates, aligned to their size: a record never straddles two cache lines, and
// the tests that read them by number (screen bins, light buffers) take one line each. The
// material, read once a hit is shaded, lies apart (PreparedScene::sphere_materials).
template <class T>
struct alignas(4 * sizeof(T)) PreparedSphere {
  Vec3<T> centre;
  T radius;
};

template <class T>
struct PreparedPlane {
  Vec3<T> normal;  // unit
  Vec3<T> point;
  int material;
  // tiled_plane: squares of `material` and `alt_material` (ambient and diffuse), on the
  // frame (u, v) or, for the 2009 form, on world x and z.
  int alt_material = -1;
  bool world_xz = false;
  Vec3<T> u{0}, v{0};
  T tile_w = 1, tile_h = 1;
  T point_scale = 0;  // largest_coordinate(point), for plane_ahead_t: set it with `point`
};

template <class T>
struct PreparedLight {
  Vec3<T> location{0};
  Vec3<T> emissivity{0};
  T scale = 0;  // largest |coordinate| of the location: sets the rounding noise of L = Lp - p
  LightKind kind = LightKind::point;
  Vec3<T> direction{0};  // spot: the cone's axis
  T cos_theta = -1;      // spot: lit where the direction to the point is within the cone
  PreparedShape<T> slide;  // projector: the window its texture lies on
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
  Rounding rounding = Rounding::nearest;  // of the film the samples go to

  std::vector<PreparedMaterial<T>> materials;
  std::vector<PreparedSphere<T>> spheres;
  std::vector<int> sphere_materials;  // per sphere
  std::vector<PreparedPlane<T>> planes;
  std::vector<PreparedShape<T>> shapes;  // object numbers after the spheres and planes
  std::vector<PreparedLight<T>> lights;
  Features features;

  Bvh bvh;                                // empty: spheres are tested in a plain loop
  // The spheres in bvh.order, and beside them each one's index in the scene (apart, so that
  // a leaf's records fill whole cache lines).
  std::vector<PreparedSphere<T>> bvh_spheres;
  std::vector<std::int32_t> bvh_index;
  // Whether `bvh` holds the other shapes too, numbered after the spheres in bvh.order: an
  // entry whose bvh_index is shape_base() or more names that shape's object (its sphere
  // unused). One walk then finds the nearest of both, where two walks each
  // crossed the scene (kinds-mix: 9 and 13 nodes a reflection ray).
  bool bvh_shapes = false;
  ScreenBins screen_bins;                 // empty: primary rays use `bvh`
  // Bins over the other shapes (entries name shapes), built with screen_bins from spheres
  // around their boxes; empty: primary rays test them through shape_bvh.
  ScreenBins shape_bins;
  std::vector<LightBuffer> light_buffers;  // per light (each may be empty), or none
  // Whether the buffers' blocker numbers below bvh.order.size() are places in bvh.order (in
  // bvh_spheres and bvh_index) rather than the numbers they were built with (sphere, then
  // shape): the spheres a shadow ray tests are then those a walk tests, side by side as the
  // hierarchy's leaves keep them, not scattered in file order (shallow-60k: 3% faster;
  // docs/performance.md). Larger numbers name the shapes the hierarchy does not hold.
  bool blockers_in_leaf_order = false;
  // Per plane (each may be empty), or none: bins over the spheres mirrored in the plane, for
  // the reflection rays primary rays send off it whose origin has no |coordinate| beyond
  // mirror_reach. Searched with the slack mirror_slack (mirror_near).
  std::vector<ScreenBins> mirror_bins;
  // The same over the other shapes (entries name shapes), per plane with mirror_bins: where
  // one is empty, those reflection rays test the shapes through shape_bvh.
  std::vector<ScreenBins> mirror_shape_bins;
  double mirror_reach = 0;
  double mirror_slack = 0;
  Bvh shape_bvh;                          // empty: the other shapes are tested in a loop

  int plane_base() const { return static_cast<int>(spheres.size()); }
  int shape_base() const { return static_cast<int>(spheres.size() + planes.size()); }
};

// Below this many spheres a plain loop beats the hierarchy (tests/bench: BM_Closest*).
inline constexpr std::size_t kBvhMinSpheres = 8;
// The other shapes cost more per test: a hierarchy pays from fewer of them.
inline constexpr std::size_t kBvhMinShapes = 4;

// Converts a checked scene for rendering. `camera` is an index into scene.cameras.
// `build_threads` (0: all cores) only changes how fast the hierarchy and the culling
// structures are built, never them.
// `spent` (optional): scene.objects itself, freed once read, before the acceleration
// structures are built, so that they reuse its memory (fresh memory is what a large scene's
// preparation costs most on the machines measured; docs/performance.md).
template <class T>
PreparedScene<T> prepare_scene(const Scene& scene, const RenderOptions& options, int camera,
                               int build_threads = 0, std::vector<Object>* spent = nullptr);

// Each object number of a prepared scene (spheres, then planes, then the other shapes, each
// in file order): its index in scene.objects.
std::vector<int> object_sources(const Scene& scene);

// Puts the spheres behind a hierarchy (whatever their number), with the other shapes where
// the scene has any (bvh_shapes); used by prepare_scene. `width` 4 or 8 (0: bvh_best_width()).
// Light buffers already numbered by the hierarchy's order (blockers_in_leaf_order) hold for
// the new one only if the spheres and shapes are those it was built from.
template <class T>
void build_sphere_bvh(PreparedScene<T>& scene, int threads, int width = 0);

}  // namespace rayfarm
