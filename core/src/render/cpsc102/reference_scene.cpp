// Loading as the reference program did: its unit vectors and plane frames, in its arithmetic.
#include "render/cpsc102/reference_scene.h"

#include <algorithm>
#include <cmath>

namespace rayfarm::cpsc102 {
namespace {

V3 v3(const glm::dvec3& v) { return {v.x, v.y, v.z}; }

// u = unit(xdir − (xdir·n) n), then n × u: the frame the .log files print.
Frame frame_of(const V3& n, const V3& xdir) {
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
    o.normal = unit(v3(p.normal));
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
  RefObject operator()(const FinitePlane& f) const {
    RefObject o;
    o.kind = RefObject::fplane;
    plane_part(o, f.plane);
    o.frame = frame_of(o.normal, v3(f.window.xdir));
    o.width = f.window.width;
    o.height = f.window.height;
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
    plane_part(o, t.plane);
    o.frame = frame_of(o.normal, v3(t.window.xdir));
    o.width = t.window.width;
    o.height = t.window.height;
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
      o.normal = unit(cross(sub(b, a), sub(c, b)));
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
    o.axis = unit(v3(r.direction));
    o.rev_height = r.height;
    return o;
  }
};

}  // namespace

RefScene prepare_reference(const Scene& scene, const RenderOptions& options, int camera) {
  const Camera& cam = scene.cameras.at(camera);
  RefScene s;
  s.width = options.width > 0 ? options.width : cam.width;
  s.height = options.height > 0 ? options.height : cam.height;
  s.world_width = cam.world_width;
  s.world_height = cam.world_height;
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
    RefObject o = std::visit(build, obj.shape);
    o.material = obj.material;
    s.objects.push_back(o);
  }
  for (const Light& l : scene.lights) {
    RefLight r;
    r.kind = l.kind;
    r.location = v3(l.location);
    r.emissivity = v3(l.emissivity);
    if (l.kind == LightKind::spot) {
      r.direction = unit(sub(v3(l.aim), r.location));
      r.cos_theta = R(std::cos(static_cast<X>(R(static_cast<X>(l.theta) * M_PI / 180))));
    } else if (l.kind == LightKind::projector) {
      r.normal = unit(v3(l.normal));
      r.point = v3(l.point);
      r.n_dot_point = dot(r.normal, r.point);
      r.frame = frame_of(r.normal, v3(l.window.xdir));
      r.width = l.window.width;
      r.height = l.window.height;
      r.texture = scene.textures.at(l.texture).image.get();
    }
    s.lights.push_back(r);
  }
  return s;
}

}  // namespace rayfarm::cpsc102
