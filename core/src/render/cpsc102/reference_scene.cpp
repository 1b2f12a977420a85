// Loading as the reference program did: its unit vectors and plane frames, in its arithmetic.
#include "render/cpsc102/reference_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include <glm/common.hpp>
#include <glm/exponential.hpp>

#include "geometry/frame.h"
#include "geometry/revsurf.h"

namespace rayfarm::cpsc102 {
namespace {

V3 v3(const glm::dvec3& v) { return {v.x, v.y, v.z}; }

// A direction the scene gives, at a length near 1 first when its square would overflow or
// underflow double (the program's own arithmetic then made no unit vector at all); every
// ordinary direction is left as the program had it.
V3 direction_unit(const V3& v) { return unit(at_unit_scale(v)); }

// u = unit(xdir − (xdir·n) n), then n × u: the frame the .log files print.
Frame frame_of(const V3& n, const V3& xdir_given) {
  const V3 xdir = at_unit_scale(xdir_given);
  const V3 u = unit(sub(xdir, scale(n, dot(xdir, n))));
  return {u, cross(n, u), n};
}

RefMaterial material_of(const Material& m) {
  RefMaterial r;
  r.ambient = v3(m.ambient);
  r.diffuse = v3(m.diffuse);
  r.specular = v3(m.specular);
  r.shininess = m.shininess.value_or(0);
  r.transparency = m.transparency;
  const double most = std::max({m.diffuse.x, m.diffuse.y, m.diffuse.z});
  for (int c = 0; c < 3; ++c)
    r.filter[c] = most > 0 ? R(R(static_cast<X>(m.transparency) * r.diffuse[c]) / most) : 0.0;
  r.reflects = m.specular.x != 0 || m.specular.y != 0 || m.specular.z != 0;
  return r;
}

struct Builder {
  const Scene& scene;

  const Image* texture(int index) const { return scene.textures.at(index).image.get(); }

  void plane_part(RefObject& o, const Plane& p) const {
    o.normal = direction_unit(v3(p.normal));
    o.point = v3(p.point);
    o.n_dot_point = dot(o.normal, o.point);
  }

  RefObject operator()(const Sphere& s) const {
    RefObject o;
    o.kind = RefObject::sphere;
    o.center = v3(s.center);
    o.radius = s.radius;
    return o;
  }
  RefObject operator()(const Plane& p) const {
    RefObject o;
    o.kind = RefObject::plane;
    plane_part(o, p);
    return o;
  }
  // A plane with a window: its frame and size.
  void window_part(RefObject& o, const Plane& p, const Window& w) const {
    plane_part(o, p);
    o.frame = frame_of(o.normal, v3(w.xdir));
    o.width = w.width;
    o.height = w.height;
  }

  RefObject operator()(const FinitePlane& f) const {
    RefObject o;
    o.kind = RefObject::fplane;
    window_part(o, f.plane, f.window);
    return o;
  }
  RefObject operator()(const TiledPlane& t) const {
    RefObject o;
    o.kind = RefObject::tiled;
    plane_part(o, t.plane);
    o.world_xz = t.world_xz;
    if (!t.world_xz) o.frame = frame_of(o.normal, v3(t.tile.xdir));
    o.width = t.tile.width;
    o.height = t.tile.height;
    o.alt_material = t.alt_material;
    return o;
  }
  RefObject operator()(const TexPlane& t) const {
    RefObject o;
    o.kind = RefObject::texplane;
    window_part(o, t.plane, t.window);
    o.texture = texture(t.texture);
    o.mode = t.mode;
    return o;
  }
  RefObject operator()(const Triangle& t) const {
    RefObject o;
    o.kind = RefObject::triangle;
    const V3 a = v3(t.vertex[0]), b = v3(t.vertex[1]), c = v3(t.vertex[2]);
    if (t.plane) {
      plane_part(o, *t.plane);
    } else {  // the 2009 tri: the plane through its vertices
      o.normal = vertex_plane_normal(a, b, c);
      o.point = a;
      o.n_dot_point = dot(o.normal, o.point);
    }
    // The vertices projected along the normal into the plane, in its frame.
    o.frame = frame_of(o.normal, sub(b, a));
    const V3 vs[3] = {a, b, c};
    for (int i = 0; i < 3; ++i) {
      const V3 q = sub(vs[i], o.point);
      o.tx[i] = dot(o.frame.row0, q);
      o.ty[i] = dot(o.frame.row1, q);
    }
    return o;
  }
  RefObject operator()(const Revsurf& r) const {
    RefObject o;
    o.kind = RefObject::revsurf;
    o.surfer = r.surfer;
    o.base = v3(r.base);
    o.axis = direction_unit(v3(r.direction));
    o.rev_height = r.height;
    return o;
  }
};

// The box in which the object's hit test can report a hit, or nullopt when that cannot be
// bounded tightly: infinite planes, and spheres so small against the scene that the
// rounding of the program's discriminant (b² − 4ac, about eps·|base − centre|²/r wide)
// could exceed the hierarchy's margin.
std::optional<BvhBox> box_of(const RefObject& o, double extent) {
  const auto around = box_around;
  auto g = [](const V3& v) { return glm::dvec3(v.x, v.y, v.z); };
  switch (o.kind) {
    case RefObject::sphere: {
      if (!(o.radius > 1e-6 * extent)) return std::nullopt;
      const glm::dvec3 c = g(o.center);
      return BvhBox{c - o.radius, c + o.radius};
    }
    case RefObject::fplane:
    case RefObject::texplane: {
      const glm::dvec3 p = g(o.point), u = g(o.frame.row0) * o.width, v = g(o.frame.row1) * o.height;
      return around({p, p + u, p + v, p + u + v});
    }
    case RefObject::triangle: {
      const glm::dvec3 p = g(o.point), u = g(o.frame.row0), v = g(o.frame.row1);
      return around({p + o.tx[0] * u + o.ty[0] * v, p + o.tx[1] * u + o.ty[1] * v,
                     p + o.tx[2] * u + o.ty[2] * v});
    }
    case RefObject::revsurf: {
      const double r = revsurf_max_radius(o.surfer, o.rev_height);
      const glm::dvec3 a = g(o.axis), b = g(o.base), top = b + o.rev_height * a;
      const glm::dvec3 ext = r * glm::sqrt(glm::max(glm::dvec3(0), 1.0 - a * a)) + 1e-9 * r;
      return around({b - ext, b + ext, top - ext, top + ext});
    }
    default:
      return std::nullopt;  // planes and tiled planes are infinite
  }
}

}  // namespace

void build_reference_bvh(RefScene& s) {
  double extent = std::max({std::abs(s.eye.x), std::abs(s.eye.y), std::abs(s.eye.z)});
  for (const RefObject& o : s.objects)
    for (const V3& v : {o.center, o.point, o.base})
      extent = std::max({extent, std::abs(v.x), std::abs(v.y), std::abs(v.z)});
  std::vector<BvhBox> boxes;
  std::vector<std::int32_t> boxed;
  s.always.clear();
  for (std::size_t k = 0; k < s.objects.size(); ++k) {
    if (auto box = box_of(s.objects[k], extent)) {
      boxes.push_back(*box);
      boxed.push_back(static_cast<std::int32_t>(k));
    } else {
      s.always.push_back(static_cast<std::int32_t>(k));
    }
  }
  BvhBuildOptions build;
  build.width = bvh_best_width();
  s.bvh = build_bvh(boxes, build);
  if (s.bvh.empty()) {  // nothing to bound, or coordinates too far out: the loop
    s.always.clear();
    return;
  }
  for (std::int32_t& i : s.bvh.order) i = boxed[i];  // leaves name objects
}

RefScene prepare_reference(const Scene& scene, const RenderOptions& options, int camera) {
  const Camera& cam = scene.cameras.at(camera);
  RefScene s;
  s.width = options.width > 0 ? options.width : cam.width;
  s.height = options.height > 0 ? options.height : cam.height;
  s.world_width = cam.world_width;
  s.world_height = cam.world_height;
  s.texel_width = R(static_cast<X>(cam.world_width) / cam.width);
  s.texel_height = R(static_cast<X>(cam.world_height) / cam.height);
  s.eye = v3(cam.viewpoint);
  for (int c = 0; c < 3; ++c) s.background[c] = std::clamp(options.background[c], 0.0, 1.0);
  s.max_dist = options.effective_max_dist();
  s.max_depth = options.effective_max_depth();
  s.spp = options.spp;
  s.seed = static_cast<std::uint32_t>(options.seed);
  s.shadows = options.shadows;
  for (const Material& m : scene.materials) s.materials.push_back(material_of(m));
  const Builder build{scene};
  for (const Object& obj : scene.objects) {
    RefObject o = visit_shape(build, obj.shape);
    o.material = obj.material;
    s.objects.push_back(o);
  }
  for (const Light& l : scene.lights) {
    RefLight r;
    r.kind = l.kind;
    r.location = v3(l.location);
    r.emissivity = v3(l.emissivity);
    if (l.kind == LightKind::spot) {
      r.direction = direction_unit(sub(v3(l.aim), r.location));
      r.cos_theta = R(std::cos(static_cast<X>(R(static_cast<X>(l.theta) * M_PI / 180))));
    } else if (l.kind == LightKind::projector) {
      r.normal = direction_unit(v3(l.normal));
      r.point = v3(l.point);
      r.n_dot_point = dot(r.normal, r.point);
      r.frame = frame_of(r.normal, v3(l.window.xdir));
      r.width = l.window.width;
      r.height = l.window.height;
      r.texture = scene.textures.at(l.texture).image.get();
    }
    s.lights.push_back(r);
  }
  if (options.specialize && s.objects.size() >= kReferenceBvhMin) build_reference_bvh(s);
  return s;
}

}  // namespace rayfarm::cpsc102
