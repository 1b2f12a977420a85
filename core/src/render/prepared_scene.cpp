// Scene preparation: conversion to the tracer's precision and the analysis of which
// pipeline parts the render needs.
#include "render/prepared_scene.h"

#include <algorithm>
#include <exception>
#include <limits>
#include <thread>

namespace rayfarm {
namespace {

// Doubles beyond float range become the largest float, never infinity.
template <class T>
T narrow(double v) {
  constexpr double kMax = static_cast<double>(std::numeric_limits<T>::max());
  return static_cast<T>(std::clamp(v, -kMax, kMax));
}

template <class T>
Vec3<T> narrow(const glm::dvec3& v) {
  return {narrow<T>(v.x), narrow<T>(v.y), narrow<T>(v.z)};
}

bool nonzero(const glm::dvec3& c) { return c.x > 0 || c.y > 0 || c.z > 0; }

}  // namespace

std::vector<std::string> Features::parts() const {
  std::vector<std::string> out{"primary"};
  if (lights) out.push_back("direct-light");
  if (shadows) out.push_back("shadows");
  if (highlight) out.push_back("highlight");
  if (reflection) out.push_back("reflection");
  if (supersampling) out.push_back("supersampling");
  if (bvh) out.push_back("bvh");
  if (screen_bins) out.push_back("screen-bins");
  if (light_buffers) out.push_back("light-buffers");
  return out;
}

template <class T>
void build_sphere_bvh(PreparedScene<T>& p, int threads) {
  std::vector<BvhBox> boxes;
  boxes.reserve(p.spheres.size());
  for (const PreparedSphere<T>& s : p.spheres) {
    const glm::dvec3 c(s.centre);
    const double r = static_cast<double>(s.radius);
    boxes.push_back({c - r, c + r});
  }
  BvhBuildOptions build;
  build.threads =
      threads > 0 ? threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  p.bvh = build_bvh(boxes, build);
  p.bvh_spheres.clear();
  if (p.bvh.empty()) return;  // coordinates out of the nodes' range: keep the loop
  p.bvh_spheres.reserve(p.spheres.size());
  for (std::int32_t i : p.bvh.order)
    p.bvh_spheres.push_back({p.spheres[i].centre, p.spheres[i].radius, i});
}

namespace {

// Builds the screen bins and (with shadows on) the light buffers, where they pay.
template <class T>
void build_ray_culling(PreparedScene<T>& p) {
  // Scales: no sphere or light has a coordinate beyond `scale`, nor the eye beyond `view`.
  auto max_abs = [](const auto& v) {
    return std::max({std::abs(static_cast<double>(v.x)), std::abs(static_cast<double>(v.y)),
                     std::abs(static_cast<double>(v.z))});
  };
  double scale = 0;
  for (const PreparedSphere<T>& s : p.spheres)
    scale = std::max(scale, max_abs(s.centre) + static_cast<double>(s.radius));
  for (const PreparedLight<T>& l : p.lights) scale = std::max(scale, max_abs(l.location));
  const double view = std::max(scale, max_abs(p.eye));
  // The tracer's sphere test and ray directions, in precision T, err by a few tens of
  // epsilons of the coordinates involved; each structure widens the spheres by 256 epsilons
  // of those: for primary rays the eye's and the scene's, for shadow rays those of points
  // within `reach` (farther ones are not answered from the buffers) and the scene's.
  const double eps = std::numeric_limits<T>::epsilon();
  const double reach = 4 * scale;
  auto widened = [&](double margin) {
    std::vector<WidenedSphere> out;
    out.reserve(p.spheres.size());
    for (const PreparedSphere<T>& s : p.spheres)
      out.push_back({glm::dvec3(s.centre), static_cast<double>(s.radius) + margin});
    return out;
  };

  // A primary ray's direction, from the pixel's screen point, errs by a few epsilons of the
  // window and eye coordinates; in pixels, padded 16-fold, plus half a pixel to spare and
  // the jitter of sampling.
  const double ww = static_cast<double>(p.world_width), wh = static_cast<double>(p.world_height);
  const double span = ww + wh + max_abs(p.eye);  // of the screen point and the eye
  const double jitter = p.spp > 1 ? 0.5 : 0.0;
  const double pad_x = 0.5 + jitter + 16 * eps * std::max(p.width - 1, 1) * span / ww;
  const double pad_y = 0.5 + jitter + 16 * eps * std::max(p.height - 1, 1) * span / wh;
  constexpr double kMaxPad = 64, kMaxCoverage = 64;
  if (pad_x <= kMaxPad && pad_y <= kMaxPad) {
    const ScreenCamera camera{glm::dvec3(p.eye), ww, wh, p.width, p.height, pad_x, pad_y};
    p.screen_bins =
        build_screen_bins(camera, widened(256 * eps * 2 * view), kTileSize, kMaxCoverage);
  }
  p.features.screen_bins = !p.screen_bins.empty();

  if (!p.features.shadows) return;
  // Each buffer costs about one pass over the spheres and a few entries per sphere: past
  // these budgets (time, and memory a small multiple of the scene's), the rest of the
  // lights keep the hierarchy.
  constexpr double kMaxWork = 8e6;
  const double max_entries = 64.0 * static_cast<double>(p.spheres.size());
  const std::size_t lights =
      std::min(p.lights.size(), static_cast<std::size_t>(kMaxWork / static_cast<double>(p.spheres.size())));
  const std::vector<WidenedSphere> spheres = widened(256 * eps * (reach + scale));
  p.light_buffers.resize(p.lights.size());
  double entries = 0;
  for (std::size_t i = 0; i < lights && entries <= max_entries; ++i) {
    p.light_buffers[i] = build_light_buffer(glm::dvec3(p.lights[i].location), spheres, reach);
    entries += static_cast<double>(p.light_buffers[i].entries.size());
    p.features.light_buffers = p.features.light_buffers || !p.light_buffers[i].empty();
  }
  if (!p.features.light_buffers) p.light_buffers.clear();
}

}  // namespace

template <class T>
PreparedScene<T> prepare_scene(const Scene& scene, const RenderOptions& options, int camera,
                               int build_threads) {
  const Camera& cam = scene.cameras.at(camera);
  PreparedScene<T> p;
  p.width = options.width > 0 ? options.width : cam.width;
  p.height = options.height > 0 ? options.height : cam.height;
  p.eye = narrow<T>(cam.viewpoint);
  p.world_width = narrow<T>(cam.world_width);
  p.world_height = narrow<T>(cam.world_height);
  // A miss is a displayable colour; clamping here keeps every sample in [0, 1].
  for (int c = 0; c < 3; ++c) p.background[c] = narrow<T>(std::clamp(options.background[c], 0.0, 1.0));
  p.max_dist = narrow<T>(options.effective_max_dist());
  p.bailout = narrow<T>(options.bailout);
  p.max_depth = options.effective_max_depth();
  p.blinn = options.highlight == Highlight::blinn;
  p.spp = options.spp;
  p.seed = options.seed;

  for (const Material& m : scene.materials) {
    PreparedMaterial<T> pm{narrow<T>(m.ambient), narrow<T>(m.diffuse), narrow<T>(m.specular),
                           narrow<T>(m.shininess),
                           narrow<T>(std::max({m.specular.x, m.specular.y, m.specular.z})),
                           nonzero(m.specular), nonzero(m.specular)};
    p.materials.push_back(pm);
  }
  for (const Sphere& s : scene.spheres)
    p.spheres.push_back({narrow<T>(s.center), narrow<T>(s.radius), s.material});
  for (const Plane& pl : scene.planes) {
    glm::dvec3 n = glm::normalize(pl.normal);
    p.planes.push_back({narrow<T>(n), narrow<T>(pl.point), pl.material});
  }
  bool any_light = false;
  for (const Light& l : scene.lights) {
    const Vec3<T> location = narrow<T>(l.location), a = glm::abs(location);
    p.lights.push_back({location, narrow<T>(l.emissivity), std::max({a.x, a.y, a.z})});
    any_light = any_light || nonzero(l.emissivity);
  }

  bool objects = !p.spheres.empty() || !p.planes.empty();
  bool reflective = false;
  for (const Sphere& s : scene.spheres) reflective |= nonzero(scene.materials[s.material].specular);
  for (const Plane& pl : scene.planes) reflective |= nonzero(scene.materials[pl.material].specular);

  Features& f = p.features;
  if (options.specialize) {
    f.lights = any_light && objects;
    f.shadows = options.shadows && f.lights;
    f.highlight = f.lights && reflective;
    f.reflection = reflective && p.max_depth > 0;
    // Without diffuse or highlight a light adds exact zeros (while E/r is finite, which the
    // tracer checks): it needs no shadow ray.
    for (size_t i = 0; i < p.materials.size(); ++i)
      p.materials[i].lit =
          nonzero(scene.materials[i].diffuse) || (f.highlight && p.materials[i].highlights);
    // The reference (unspecialized) path always loops, so tests compare the two. The
    // hierarchy and the culling structures are independent: with two threads or more they
    // are built side by side.
    if (p.spheres.size() >= kBvhMinSpheres) {
      const int threads =
          build_threads > 0 ? build_threads
                            : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
      if (threads > 1) {
        std::exception_ptr failure;  // (out of memory) rethrown here, not on the thread
        std::thread culling([&] {
          try {
            build_ray_culling(p);
          } catch (...) {
            failure = std::current_exception();
          }
        });
        build_sphere_bvh(p, threads - 1);
        culling.join();
        if (failure) std::rethrow_exception(failure);
      } else {
        build_ray_culling(p);
        build_sphere_bvh(p, 1);
      }
    }
    f.bvh = !p.bvh.empty();
  } else {
    f.lights = true;
    f.shadows = options.shadows;
    f.highlight = true;
    f.reflection = true;
    for (auto& m : p.materials) m.reflects = m.highlights = true;
  }
  f.supersampling = options.spp > 1;
  return p;
}

template PreparedScene<float> prepare_scene<float>(const Scene&, const RenderOptions&, int, int);
template PreparedScene<double> prepare_scene<double>(const Scene&, const RenderOptions&, int, int);
template void build_sphere_bvh<float>(PreparedScene<float>&, int);
template void build_sphere_bvh<double>(PreparedScene<double>&, int);

}  // namespace rayfarm
