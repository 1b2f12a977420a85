// Scene preparation: conversion to the tracer's precision and the analysis of which
// pipeline parts the render needs.
#include "render/prepared_scene.h"

#include "geometry/frame.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <functional>
#include <limits>
#include <mutex>
#include <thread>
#include <variant>

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

// The lecture's shininess when a material gives none (docs/model-format.md#materials).
constexpr double kLectureShininess = 32;

// A frame the builder checked exists (geometry/frame.h).
PlaneFrame frame_of(const glm::dvec3& normal, const glm::dvec3& xdir) {
  return *plane_frame(normal, xdir);
}

// The bounded shapes other than spheres, from the scene's objects.
template <class T>
struct ShapeMaker {
  const Scene& scene;
  const Camera& camera;

  PreparedShape<T> window(typename PreparedShape<T>::Kind kind, const Plane& plane,
                          const Window& w) const {
    const PlaneFrame f = frame_of(plane.normal, w.xdir);
    PreparedShape<T> s;
    s.kind = kind;
    s.normal = narrow<T>(f.n);
    s.point = narrow<T>(plane.point);
    s.point_scale = largest_coordinate(s.point);
    s.u = narrow<T>(f.u);
    s.v = narrow<T>(f.v);
    s.width = narrow<T>(w.width);
    s.height = narrow<T>(w.height);
    return s;
  }

  std::optional<PreparedShape<T>> operator()(const FinitePlane& f) const {
    return window(PreparedShape<T>::finite_plane, f.plane, f.window);
  }
  std::optional<PreparedShape<T>> operator()(const TexPlane& t) const {
    PreparedShape<T> s = window(PreparedShape<T>::tex_plane, t.plane, t.window);
    s.texture = scene.textures.at(t.texture).image.get();
    s.mode = t.mode;
    // One texel per pixel of the camera's own size, whatever size is rendered.
    s.pixel_w = narrow<T>(camera.world_width / camera.width);
    s.pixel_h = narrow<T>(camera.world_height / camera.height);
    return s;
  }
  std::optional<PreparedShape<T>> operator()(const Triangle& t) const {
    const Plane plane = t.plane ? *t.plane
                                : Plane{glm::cross(t.vertex[1] - t.vertex[0],
                                                   t.vertex[2] - t.vertex[1]),
                                        t.vertex[0]};
    // The frame's x axis along an edge that has a part in the plane (one has: the builder
    // refuses triangles without area).
    glm::dvec3 xdir = t.vertex[1] - t.vertex[0];
    for (const glm::dvec3& edge : {t.vertex[2] - t.vertex[0], t.vertex[2] - t.vertex[1]})
      if (!plane_frame(plane.normal, xdir)) xdir = edge;
    PreparedShape<T> s = window(PreparedShape<T>::triangle, plane, {xdir, 0, 0});
    const PlaneFrame f = frame_of(plane.normal, xdir);
    for (int i = 0; i < 3; ++i) {
      const glm::dvec3 q = t.vertex[i] - plane.point;
      s.tx[i] = narrow<T>(glm::dot(f.u, q));
      s.ty[i] = narrow<T>(glm::dot(f.v, q));
    }
    return s;
  }
  std::optional<PreparedShape<T>> operator()(const Revsurf& r) const {
    PreparedShape<T> s;
    s.kind = PreparedShape<T>::revsurf;
    s.point = narrow<T>(r.base);
    s.normal = narrow<T>(unit_direction(r.direction));
    s.height = narrow<T>(r.height);
    s.surfer = r.surfer;
    // Around the cylinder of the part that exists, from the prepared (rounded) values the
    // search itself uses.
    const double top = revsurf_top(s.surfer, static_cast<double>(s.height));
    const double rmax = revsurf_max_radius(s.surfer, top);
    s.bound_centre = glm::dvec3(s.point) + (top / 2) * glm::dvec3(s.normal);
    s.bound_radius = std::sqrt(top * top / 4 + rmax * rmax);
    return s;
  }
  template <class Other>
  std::optional<PreparedShape<T>> operator()(const Other&) const {
    return std::nullopt;  // spheres and planes have their own arrays
  }
};

// The box of a bounded shape, in double.
template <class T>
BvhBox shape_box(const PreparedShape<T>& s) {
  const glm::dvec3 o(s.point), u(s.u), v(s.v), a(s.normal);
  const auto box_of = box_around;
  if (s.kind == PreparedShape<T>::revsurf) {
    const double r = revsurf_max_radius(s.surfer, static_cast<double>(s.height));
    const glm::dvec3 top = o + static_cast<double>(s.height) * a;
    const glm::dvec3 ext = r * glm::sqrt(glm::max(glm::dvec3(0), 1.0 - a * a));
    return box_of({o - ext, o + ext, top - ext, top + ext});
  }
  if (s.kind == PreparedShape<T>::triangle) {
    glm::dvec3 q[3];
    for (int i = 0; i < 3; ++i)
      q[i] = o + static_cast<double>(s.tx[i]) * u + static_cast<double>(s.ty[i]) * v;
    return box_of({q[0], q[1], q[2]});
  }
  const double w = static_cast<double>(s.width), h = static_cast<double>(s.height);
  return box_of({o, o + w * u, o + h * v, o + w * u + h * v});
}

// Puts the other shapes behind a hierarchy of their own.
template <class T>
void build_shape_bvh(PreparedScene<T>& p) {
  std::vector<BvhBox> boxes;
  boxes.reserve(p.shapes.size());
  for (const PreparedShape<T>& s : p.shapes) boxes.push_back(shape_box(s));
  BvhBuildOptions build;
  build.width = bvh_best_width();
  p.shape_bvh = build_bvh(boxes, build);
}

}  // namespace

std::vector<std::string> Features::parts() const {
  std::vector<std::string> out{"primary"};
  if (lights) out.push_back("direct-light");
  if (shadows) out.push_back("shadows");
  if (highlight) out.push_back("highlight");
  if (reflection) out.push_back("reflection");
  if (transparency) out.push_back("transparency");
  if (supersampling) out.push_back("supersampling");
  if (bvh) out.push_back("bvh");
  if (screen_bins) out.push_back("screen-bins");
  if (light_buffers) out.push_back("light-buffers");
  if (mirror_bins) out.push_back("mirror-bins");
  if (byte_cutoff) out.push_back("byte-cutoff");
  return out;
}

template <class T>
void build_sphere_bvh(PreparedScene<T>& p, int threads, int width) {
  BvhBuildOptions build;
  build.width = width > 0 ? width : bvh_best_width();
  build.threads =
      threads > 0 ? threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  // Subtrees of up to 8 spheres as one leaf where the surface area heuristic prices that
  // below a node (most bottom nodes held two single spheres): render 0-11% faster on the
  // benchmark scenes, none slower (docs/performance.md). The other shapes, dearer to
  // test, keep leaves of their own.
  build.merge_max = 8;
  build.merge_below = p.spheres.size();
  auto sphere_box = [&](std::size_t i) {
    const glm::dvec3 c(p.spheres[i].centre);
    const double r = static_cast<double>(p.spheres[i].radius);
    return BvhBox{c - r, c + r};
  };
  // The other shapes with the spheres where their boxes fit the nodes; else the spheres alone.
  const std::size_t ns = p.spheres.size();
  p.bvh = Bvh{};
  if (!p.shapes.empty())
    p.bvh = build_bvh(
        ns + p.shapes.size(),
        [&](std::size_t i) { return i < ns ? sphere_box(i) : shape_box(p.shapes[i - ns]); }, build);
  p.bvh_shapes = !p.bvh.empty();
  if (!p.bvh_shapes) p.bvh = build_bvh(ns, sphere_box, build);
  p.bvh_spheres.clear();
  p.bvh_index.clear();
  if (p.bvh.empty()) return;  // coordinates out of the nodes' range: keep the loop
  p.bvh_spheres.reserve(p.bvh.order.size());
  p.bvh_index.reserve(p.bvh.order.size());
  const std::int32_t shape_base = p.shape_base();
  for (std::int32_t i : p.bvh.order) {
    if (i < static_cast<std::int32_t>(ns)) {
      p.bvh_spheres.push_back(p.spheres[i]);
      p.bvh_index.push_back(i);
    } else {
      p.bvh_spheres.push_back({Vec3<T>(0), T(0)});
      p.bvh_index.push_back(shape_base + (i - static_cast<std::int32_t>(ns)));
    }
  }
}

namespace {

// The scene's spheres, each widened by `margin`.
template <class T>
std::vector<WidenedSphere> widened_spheres(const PreparedScene<T>& p, double margin) {
  std::vector<WidenedSphere> out;
  out.reserve(p.spheres.size());
  for (const PreparedSphere<T>& s : p.spheres)
    out.push_back({glm::dvec3(s.centre), static_cast<double>(s.radius) + margin});
  return out;
}

// The spheres around the other shapes' boxes, for the screen and mirror bins and the light
// buffers, and the largest |coordinate| of any box (`scale`). Each use widens them like the
// spheres, by some epsilons of the coordinates involved, which covers the rounding of the
// point a shape test finds (it lies on the ray, and within that of the shape).
struct ShapeBounds {
  std::vector<WidenedSphere> tight;
  double scale = 0;

  std::vector<WidenedSphere> widened(double margin) const {
    std::vector<WidenedSphere> out = tight;
    for (WidenedSphere& s : out) s.radius += margin;
    return out;
  }
};

template <class T>
ShapeBounds shape_bounds(const PreparedScene<T>& p) {
  ShapeBounds out;
  out.tight.reserve(p.shapes.size());
  for (const PreparedShape<T>& s : p.shapes) {
    const BvhBox b = shape_box(s);
    // The shape's tests work from its point, which may lie far outside its box (a triangle
    // in a plane written through a point 1e17 away): their rounding is of that size.
    for (const glm::dvec3& c : {b.lo, b.hi, glm::dvec3(s.point)})
      out.scale = std::max({out.scale, std::abs(c.x), std::abs(c.y), std::abs(c.z)});
    out.tight.push_back({(b.lo + b.hi) / 2.0, glm::length(b.hi - b.lo) / 2});
  }
  return out;
}

// The ray-culling structures: the screen bins, the mirror bins and (with shadows on) the
// light buffers, where they pay. The screen bins from a single shape on (primary rays then
// test a shape only on the pixels it covers: a flat shape's test divides, a surface of
// revolution's searches; lab 1.55 -> 1.36 G instructions), the rest only with the sphere
// hierarchy. Each bins set or buffer is a task of its own, so that a thread done with the
// hierarchy can take the ones left (lights-inside-50k: hierarchy 32 ms, the rest 42 ms on
// one thread); what each builds does not depend on which thread builds it, or when.
template <class T>
class RayCulling {
 public:
  explicit RayCulling(PreparedScene<T>& p) : p_(p) {
    // Scales: no sphere or light has a coordinate beyond `scale_`, nor the eye beyond `view_`.
    auto max_abs = [](const auto& v) {
      return std::max({std::abs(static_cast<double>(v.x)), std::abs(static_cast<double>(v.y)),
                       std::abs(static_cast<double>(v.z))});
    };
    for (const PreparedSphere<T>& s : p.spheres)
      scale_ = std::max(scale_, max_abs(s.centre) + static_cast<double>(s.radius));
    for (const PreparedLight<T>& l : p.lights) scale_ = std::max(scale_, max_abs(l.location));
    view_ = std::max(scale_, max_abs(p.eye));
    shapes_ = shape_bounds(p);
    // A primary ray's direction, from the pixel's screen point, errs by a few epsilons of the
    // window and eye coordinates; in pixels, padded 16-fold, plus half a pixel to spare and
    // the jitter of sampling.
    const double ww = static_cast<double>(p.world_width), wh = static_cast<double>(p.world_height);
    const double span = ww + wh + max_abs(p.eye);  // of the screen point and the eye
    const double jitter = p.spp > 1 ? 0.5 : 0.0;
    pad_x_ = 0.5 + jitter + 16 * kEps * std::max(p.width - 1, 1) * span / ww;
    pad_y_ = 0.5 + jitter + 16 * kEps * std::max(p.height - 1, 1) * span / wh;
    const bool padded = pad_x_ <= kMaxPad && pad_y_ <= kMaxPad;
    if (padded) tasks_.push_back([this] { screen_bins(); });
    // The rest stands in for the sphere hierarchy: where there is none, the loop is cheaper.
    if (p.spheres.size() < kBvhMinSpheres) return;
    if (padded && p.features.reflection && p.max_depth >= 1) {
      p.mirror_reach = 4 * view_;
      // The sphere test's near root can fall short by about sqrt(epsilon) of the distance.
      p.mirror_slack = 16 * std::sqrt(kEps);
      p.mirror_bins.resize(p.planes.size());
      if (!shapes_.tight.empty()) p.mirror_shape_bins.resize(p.planes.size());
      for (std::size_t j = 0; j < p.planes.size(); ++j) {
        const PreparedMaterial<T>& m = p.materials[p.planes[j].material];
        if (m.reflects && !(m.max_specular < p.bailout))  // else it sends no reflection rays
          tasks_.push_back([this, j] { mirror_bins(j); });
      }
    }
    // Light buffers answer "is anything in the way"; through translucent objects the shadow
    // ray must find every one on its way, so they step aside.
    if (!p.features.shadows || p.features.transparency) return;
    // Each buffer costs about one pass over the blockers (the spheres, then the spheres about
    // the other shapes) and a few entries per blocker: past a time budget the rest of the
    // lights keep the hierarchies (and past a memory budget, finish()).
    constexpr double kMaxWork = 8e6;
    const double count = static_cast<double>(p.spheres.size() + p.shapes.size());
    const std::size_t lights =
        std::min(p.lights.size(), static_cast<std::size_t>(kMaxWork / count));
    p.light_buffers.resize(p.lights.size());
    for (std::size_t i = 0; i < lights; ++i) tasks_.push_back([this, i] { light_buffer(i); });
  }

  // Takes tasks until none is left; from any number of threads.
  void run() {
    for (std::size_t k; (k = next_.fetch_add(1, std::memory_order_relaxed)) < tasks_.size();)
      tasks_[k]();
  }

  // After every run(): what was built is kept where it pays, and said in the features.
  void finish() {
    PreparedScene<T>& p = p_;
    p.features.screen_bins = !p.screen_bins.empty();
    const bool mirrors = std::any_of(p.mirror_bins.begin(), p.mirror_bins.end(),
                                     [](const ScreenBins& b) { return !b.empty(); });
    if (!mirrors) {
      p.mirror_bins.clear();
      p.mirror_shape_bins.clear();
    }
    p.features.mirror_bins = mirrors;
    // Memory a small multiple of the scene's: the lights after the budget is spent keep the
    // hierarchies (as if the buffers were built in light order until then).
    const double max_entries = 64.0 * static_cast<double>(p.spheres.size() + p.shapes.size());
    double entries = 0;
    for (LightBuffer& lb : p.light_buffers) {
      if (entries > max_entries) lb = LightBuffer{};
      entries += static_cast<double>(lb.entries.size());
      p.features.light_buffers = p.features.light_buffers || !lb.empty();
    }
    if (!p.features.light_buffers) p.light_buffers.clear();
  }

 private:
  static constexpr double kEps = std::numeric_limits<T>::epsilon();
  static constexpr double kMaxPad = 64, kMaxCoverage = 64;

  ScreenCamera camera() const {
    return {glm::dvec3(p_.eye), static_cast<double>(p_.world_width),
            static_cast<double>(p_.world_height), p_.width, p_.height, pad_x_, pad_y_};
  }

  // The tracer's sphere test and ray directions, in precision T, err by a few tens of
  // epsilons of the coordinates involved; each structure widens the spheres by 256 epsilons
  // of those: for primary rays the eye's and the scene's.
  void screen_bins() {
    p_.screen_bins = build_screen_bins(camera(), widened_spheres(p_, 256 * kEps * 2 * view_),
                                       kTileSize, kMaxCoverage);
    if (!p_.screen_bins.empty() && !p_.shapes.empty())
      p_.shape_bins = build_screen_bins(
          camera(), shapes_.widened(256 * kEps * 2 * std::max(view_, shapes_.scale)), kTileSize,
          kMaxCoverage);
  }

  // Mirror bins for plane j, which reflects primary rays (mirror_bins.h). The real reflection
  // ray strays from the mirrored primary ray by tens of epsilons of |eye|, |p| and the
  // plane's point (origin) plus tens of epsilons per unit of length (direction), and the
  // sphere test errs by tens of epsilons of the coordinates: spheres are widened by 1024
  // epsilons of all of them together, for origins p within `reach`. The other shapes get bins
  // of their own, from the spheres about their boxes widened likewise (with their coordinates
  // among the scales: a shape's hit lies in its box, so the ray is at most |p| + those long
  // there).
  void mirror_bins(std::size_t j) {
    const PreparedPlane<T>& pl = p_.planes[j];
    const double reach = p_.mirror_reach;
    const glm::dvec3 q(pl.point);
    const double plane_scale = std::max({std::abs(q.x), std::abs(q.y), std::abs(q.z)});
    const double margin = 1024 * kEps * (reach + view_ + scale_ + plane_scale);
    p_.mirror_bins[j] = build_mirror_bins(camera(), widened_spheres(p_, margin),
                                          glm::dvec3(pl.normal), q, kTileSize, kMaxCoverage);
    if (p_.mirror_bins[j].empty() || shapes_.tight.empty()) return;
    const double shape_margin =
        1024 * kEps * (reach + view_ + std::max(scale_, shapes_.scale) + plane_scale);
    p_.mirror_shape_bins[j] = build_mirror_bins(camera(), shapes_.widened(shape_margin),
                                                glm::dvec3(pl.normal), q, kTileSize, kMaxCoverage);
  }

  // For shadow rays, points within `reach` (farther ones are not answered from the buffers)
  // and the scene's scale. The other shapes go in too, after the spheres (LightBuffer's
  // blocker numbers), so that a shadow ray the buffer answers needs no walk of their
  // hierarchy: a shape's hit on the segment lies in the sphere about its box, which is
  // listed wherever that segment can go.
  void light_buffer(std::size_t i) {
    const double reach = 4 * scale_;
    std::call_once(blockers_once_, [&] {
      blockers_ = widened_spheres(p_, 256 * kEps * (reach + scale_));
      const std::vector<WidenedSphere> more =
          shapes_.widened(256 * kEps * (reach + std::max(scale_, shapes_.scale)));
      blockers_.insert(blockers_.end(), more.begin(), more.end());
    });
    p_.light_buffers[i] = build_light_buffer(glm::dvec3(p_.lights[i].location), blockers_, reach);
  }

  PreparedScene<T>& p_;
  double scale_ = 0, view_ = 0, pad_x_ = 0, pad_y_ = 0;
  ShapeBounds shapes_;
  std::vector<std::function<void()>> tasks_;
  std::atomic<std::size_t> next_{0};
  std::once_flag blockers_once_;
  std::vector<WidenedSphere> blockers_;
};

// All of them on this thread.
template <class T>
void build_ray_culling(PreparedScene<T>& p) {
  RayCulling<T> culling(p);
  culling.run();
  culling.finish();
}

// Whether a path's colour is a monotone function of each ray it has yet to follow, with values
// under Tracer::value_bound: the weights of the fold (specular, keep = 1 - transparency,
// filter) finite and not negative, no transparency within 2^-8 of 1 unless it is 1, and no
// filter above its transparency but by rounding (at most 1 where that is 1). The last fails
// only where a diffuse colour is subnormal: transparency · diffuse then rounds to a far larger
// share of it (0.6 · 2^-1074 is 2^-1074, a filter of 1 beside a keep of 0.4).
template <class T>
bool bounded_weights(const Scene& scene, const PreparedScene<T>& p) {
  for (std::size_t i = 0; i < p.materials.size(); ++i) {
    const double tr = scene.materials[i].transparency;
    if (!(tr == 0 || tr == 1 || (tr > 0 && tr <= 1 - 1.0 / 256))) return false;
    const double most_filter = tr == 1 ? 1.0 : tr * (1 + 1.0 / (1 << 20));
    const PreparedMaterial<T>& m = p.materials[i];
    for (int c = 0; c < 3; ++c)
      if (!(m.specular[c] >= 0 && std::isfinite(m.specular[c]) && m.filter[c] >= 0 &&
            static_cast<double>(m.filter[c]) <= most_filter))
        return false;
  }
  return true;
}

// Renumbers the light buffers' blockers to places in the hierarchy's order (see
// PreparedScene::blockers_in_leaf_order). Both are built by then, on whichever threads.
template <class T>
void renumber_blockers(PreparedScene<T>& p) {
  if (p.light_buffers.empty() || p.bvh.empty()) return;
  // The hierarchy numbers what it holds as the buffers do: the spheres, then the shapes.
  const std::size_t n = p.bvh.order.size();
  std::vector<std::int32_t> place(n);
  for (std::size_t k = 0; k < n; ++k) place[p.bvh.order[k]] = static_cast<std::int32_t>(k);
  auto renumber = [&](std::int32_t& blocker) {
    if (static_cast<std::size_t>(blocker) < n) blocker = place[blocker];
  };
  for (LightBuffer& lb : p.light_buffers) {
    for (LightBufferEntry& e : lb.entries) renumber(e.blocker);
    for (std::int32_t& b : lb.around) renumber(b);
  }
  p.blockers_in_leaf_order = true;
}

}  // namespace

template <class T>
PreparedScene<T> prepare_scene(const Scene& scene, const RenderOptions& options, int camera,
                               int build_threads, std::vector<Object>* spent) {
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
  p.rounding = options.effective_rounding();

  for (const Material& m : scene.materials) {
    PreparedMaterial<T> pm{narrow<T>(m.ambient), narrow<T>(m.diffuse), narrow<T>(m.specular),
                           narrow<T>(m.shininess.value_or(kLectureShininess)),
                           narrow<T>(std::max({m.specular.x, m.specular.y, m.specular.z})),
                           nonzero(m.specular), nonzero(m.specular)};
    pm.transparency = narrow<T>(m.transparency);
    bound_highlight(pm);
    const double most = std::max({m.diffuse.x, m.diffuse.y, m.diffuse.z});
    if (most > 0) pm.filter = narrow<T>(m.transparency * m.diffuse / most);
    p.materials.push_back(pm);
  }
  const ShapeMaker<T> make{scene, cam};
  // Room for all at once, not grown by doubling (which copies the array through every
  // smaller block on the way). Then the objects in one pass: each pass over a large scene's
  // objects reads megabytes again (shallow-60k: 8 MB, six passes took 5 ms before the
  // structures' builds could start; docs/performance.md).
  const std::size_t sphere_count = scene.count<Sphere>();
  p.spheres.reserve(sphere_count);
  p.sphere_materials.reserve(sphere_count);
  bool reflective = false, translucent = false;
  for (const Object& o : scene.objects) {
    reflective |= nonzero(scene.materials[o.material].specular);
    translucent |= scene.materials[o.material].transparency > 0;
    if (const Sphere* s = o.as<Sphere>()) {
      p.spheres.push_back({narrow<T>(s->center), narrow<T>(s->radius)});
      p.sphere_materials.push_back(o.material);
    } else if (const Plane* pl = o.as<Plane>()) {
      p.planes.push_back({narrow<T>(unit_direction(pl->normal)), narrow<T>(pl->point), o.material});
    } else if (const TiledPlane* t = o.as<TiledPlane>()) {
      PreparedPlane<T> pp{narrow<T>(unit_direction(t->plane.normal)), narrow<T>(t->plane.point),
                          o.material};
      pp.alt_material = t->alt_material;
      pp.world_xz = t->world_xz;
      if (!t->world_xz) {
        const PlaneFrame f = frame_of(t->plane.normal, t->tile.xdir);
        pp.u = narrow<T>(f.u);
        pp.v = narrow<T>(f.v);
      }
      pp.tile_w = narrow<T>(t->tile.width);
      pp.tile_h = narrow<T>(t->tile.height);
      p.planes.push_back(pp);
    } else if (auto shape = visit_shape(make, o.shape)) {
      shape->material = o.material;
      p.shapes.push_back(*shape);
    }
  }
  for (PreparedPlane<T>& pl : p.planes) pl.point_scale = largest_coordinate(pl.point);
  bool any_light = false;
  for (const Light& l : scene.lights) {
    const Vec3<T> location = narrow<T>(l.location);
    PreparedLight<T> pl;
    pl.location = location;
    pl.emissivity = narrow<T>(l.emissivity);
    pl.scale = largest_coordinate(location);
    pl.kind = l.kind;
    if (l.kind == LightKind::spot) {
      pl.direction = narrow<T>(unit_direction(l.aim - l.location));
      pl.cos_theta = narrow<T>(std::cos(l.theta * M_PI / 180));
    } else if (l.kind == LightKind::projector) {
      pl.slide = make.window(PreparedShape<T>::tex_plane, {l.normal, l.point}, l.window);
      pl.slide.texture = scene.textures.at(l.texture).image.get();
      pl.slide.mode = l.mode;
    }
    p.lights.push_back(pl);
    any_light = any_light || nonzero(l.emissivity);
  }

  const bool objects = !scene.objects.empty();
  if (spent) std::vector<Object>().swap(*spent);  // nothing below reads the objects

  Features& f = p.features;
  f.transparency = translucent;  // before build_ray_culling, which leaves the light buffers out
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
    // A tiled plane shades with its other material's diffuse on half its squares.
    for (const PreparedPlane<T>& pl : p.planes)
      if (pl.alt_material >= 0 && nonzero(scene.materials[pl.alt_material].diffuse))
        p.materials[pl.material].lit = true;
    // The reference (unspecialized) path always loops, so tests compare the two. The
    // hierarchy and the culling structures are independent: with two threads or more they
    // are built side by side. Shapes alone ask for the screen bins (build_ray_culling).
    if (p.spheres.size() < kBvhMinSpheres) {
      if (!p.shapes.empty()) build_ray_culling(p);
    } else {
      const int threads =
          build_threads > 0 ? build_threads
                            : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
      if (threads > 1) {
        // The hierarchy here, the culling structures on another thread; this one takes the
        // culling tasks left once the hierarchy is built.
        RayCulling<T> culling(p);
        std::exception_ptr failure;  // (out of memory) rethrown here, not on the thread
        std::thread helper([&] {
          try {
            culling.run();
          } catch (...) {
            failure = std::current_exception();
          }
        });
        try {
          build_sphere_bvh(p, threads - 1);
          culling.run();
        } catch (...) {
          helper.join();
          throw;
        }
        helper.join();
        if (failure) std::rethrow_exception(failure);
        culling.finish();
      } else {
        build_ray_culling(p);
        build_sphere_bvh(p, 1);
      }
      renumber_blockers(p);
    }
    f.bvh = !p.bvh.empty();
    if (p.shapes.size() >= kBvhMinShapes) build_shape_bvh(p);
    f.bvh = f.bvh || !p.shape_bvh.empty();
    f.byte_cutoff = (f.reflection || f.transparency) && p.max_depth > 0 && options.spp == 1 &&
                    bounded_weights(scene, p);
  } else {
    f.lights = true;
    f.shadows = options.shadows;
    f.highlight = true;
    f.reflection = true;
    // Every highlight computed in full too: the specialized renders are compared with these.
    for (auto& m : p.materials) {
      m.reflects = m.highlights = true;
      m.highlight_bounded = false;
    }
  }
  f.supersampling = options.spp > 1;
  return p;
}

std::vector<int> object_sources(const Scene& scene) {
  std::vector<int> out;
  out.reserve(scene.objects.size());
  auto add = [&](auto&& belongs) {
    for (std::size_t i = 0; i < scene.objects.size(); ++i)
      if (belongs(scene.objects[i])) out.push_back(static_cast<int>(i));
  };
  auto sphere = [](const Object& o) { return o.as<Sphere>() != nullptr; };
  auto plane = [](const Object& o) { return o.as<Plane>() || o.as<TiledPlane>(); };
  add(sphere);
  add(plane);
  add([&](const Object& o) { return !sphere(o) && !plane(o); });
  return out;
}

template PreparedScene<float> prepare_scene<float>(const Scene&, const RenderOptions&, int, int,
                                                   std::vector<Object>*);
template PreparedScene<double> prepare_scene<double>(const Scene&, const RenderOptions&, int, int,
                                                     std::vector<Object>*);
template void build_sphere_bvh<float>(PreparedScene<float>&, int, int);
template void build_sphere_bvh<double>(PreparedScene<double>&, int, int);

}  // namespace rayfarm
