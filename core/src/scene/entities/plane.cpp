// The plane kinds: plane, fplane (a rectangle of a plane), tiled_plane (a plane of squares of
// two materials) and texplane (a rectangle with an image on it).
#include <array>

#include "scene/entities/plane_parts.h"

namespace rayfarm::entities {
namespace {

using V = ValueKind;
constexpr AttrSpec kPlaneAttrs[] = {
    {"material", V::material_ref, true},
    {"normal", V::direction, true},
    {"point", V::point, true},
};
constexpr AttrSpec kFinitePlaneAttrs[] = {
    {"material", V::material_ref, true},
    {"normal", V::direction, true},
    {"point", V::point, true},
    {"xdir", V::direction, true},
    {"dimensions", V::window_dims, true},
};
// Two forms: `xdir` + `dimensions` (tiles in the plane's own frame), or the 2009 course's
// `dimension` alone (squares on the world's x and z).
constexpr AttrSpec kTiledPlaneAttrs[] = {
    {"material", V::material_ref, true},
    {"normal", V::direction, true},
    {"point", V::point, true},
    {"xdir", V::direction, false},
    {"dimensions", V::window_dims, false},
    {"dimension", V::window_dims, false},
    {"altmaterial", V::material_ref, true},
};
constexpr AttrSpec kTexPlaneAttrs[] = {
    {"material", V::material_ref, true},
    {"normal", V::direction, true},
    {"point", V::point, true},
    {"xdir", V::direction, true},
    {"dimensions", V::window_dims, true},
    {"texname", V::word, true},
    {"mode", V::integer, false, {0, 0, 0}, 0, 1},
};

void build_plane(EntityReader& r, Scene& scene) {
  auto plane = read_plane(r);
  auto m = r.material("material");
  if (!plane || !m) return;
  scene.objects.push_back(r.object(*m, *plane));
}

void build_fplane(EntityReader& r, Scene& scene) {
  auto plane = read_plane(r);
  auto m = r.material("material");
  auto window = read_window(r, plane);
  if (!plane || !m || !window) return;
  scene.objects.push_back(r.object(*m, FinitePlane{*plane, *window}));
}

void build_tiled(EntityReader& r, Scene& scene) {
  auto plane = read_plane(r);
  auto m = r.material("material"), alt = r.material("altmaterial");
  const bool modern = r.has("xdir") || r.has("dimensions");
  if (modern && r.has("dimension")) {
    r.error("conflicting-attributes",
            "give either 'xdir' and 'dimensions' or the 2009 form 'dimension', not both",
            r.find("dimension")->where);
    return;
  }
  TiledPlane t{plane.value_or(Plane{}), {}, !modern, alt.value_or(0)};
  if (modern) {
    for (std::string_view key : {"xdir", "dimensions"})
      if (!r.has(key)) {
        r.error_at_entity("missing-attribute", r.describe() + " is missing '" + std::string(key) +
                                                   "' (it has '" +
                                                   (key == "xdir" ? "dimensions" : "xdir") +
                                                   "': the tiles' frame needs both)");
        return;
      }
    auto window = read_window(r, plane);
    if (!window) return;
    t.tile = *window;
  } else {
    auto size = r.pair("dimension");
    if (!r.has("dimension")) {
      r.error_at_entity("missing-attribute",
                        r.describe() + " is missing the tile size: 'xdir' and 'dimensions' (or "
                                       "the 2009 form 'dimension')");
      return;
    }
    if (!size) return;
    t.tile = {{1, 0, 0}, (*size)[0], (*size)[1]};
  }
  if (!plane || !m || !alt) return;
  scene.objects.push_back(r.object(*m, t));
}

void build_texplane(EntityReader& r, Scene& scene) {
  auto plane = read_plane(r);
  auto m = r.material("material");
  auto texture = r.texture("texname");
  auto mode = r.integer("mode");
  auto window = read_window(r, plane);
  if (!plane || !m || !texture || !mode || !window) return;
  scene.objects.push_back(r.object(*m, TexPlane{*plane, *window, *texture, *mode}));
}

// The window's corners, counter-clockwise from `point`.
std::array<glm::dvec3, 4> corners(const Plane& plane, const Window& w) {
  const PlaneFrame f = *plane_frame(plane.normal, w.xdir);  // checked when built
  const glm::dvec3 u = f.u, v = f.v, p = plane.point;
  return {p, p + w.width * u, p + w.width * u + w.height * v, p + w.height * v};
}

void pov_plane_part(PovWriter& w, const Plane& p) {
  const glm::dvec3 n = unit_direction(PovWriter::flip(p.normal));
  w.out << "plane { " << w.vec(n) << ", " << w.num(glm::dot(n, PovWriter::flip(p.point)));
}

void pov_polygon(PovWriter& w, const Plane& plane, const Window& win) {
  const auto c = corners(plane, win);
  w.out << "polygon { 5, " << w.at(c[0]) << ", " << w.at(c[1]) << ", " << w.at(c[2]) << ", "
        << w.at(c[3]) << ", " << w.at(c[0]);
}

void pov_plane(PovWriter& w, int index) {
  const Object& o = w.scene.objects[index];
  pov_plane_part(w, *o.as<Plane>());
  w.out << " " << w.texture(o.material) << " }\n";
}

void pov_fplane(PovWriter& w, int index) {
  const Object& o = w.scene.objects[index];
  const FinitePlane& f = *o.as<FinitePlane>();
  pov_polygon(w, f.plane, f.window);
  w.out << " " << w.texture(o.material) << " }\n";
}

// POV-Ray's checker alternates unit cubes: scaled to a tile and turned into the plane's frame.
void pov_tiled(PovWriter& w, int index) {
  const Object& o = w.scene.objects[index];
  const TiledPlane& t = *o.as<TiledPlane>();
  pov_plane_part(w, t.plane);
  glm::dvec3 u{1, 0, 0}, v{0, 0, 1}, n{0, 1, 0};
  if (!t.world_xz) {
    const PlaneFrame f = *plane_frame(t.plane.normal, t.tile.xdir);
    n = f.n;
    u = f.u;
    v = f.v;
  }
  const glm::dvec3 a = PovWriter::flip(u) * t.tile.width, b = PovWriter::flip(v) * t.tile.height,
                   c = PovWriter::flip(n);
  w.out << " texture { checker " << w.texture(t.alt_material) << " " << w.texture(o.material)
        << " matrix <" << w.num(a.x) << ", " << w.num(a.y) << ", " << w.num(a.z) << ", "
        << w.num(b.x) << ", " << w.num(b.y) << ", " << w.num(b.z) << ", " << w.num(c.x) << ", "
        << w.num(c.y) << ", " << w.num(c.z) << ", 0, 0, 0> } }\n";
}

// The image over the window (mode 0) or repeated (mode 1), as POV-Ray maps an image_map onto
// the unit square of the x-y plane.
void pov_texplane(PovWriter& w, int index) {
  const Object& o = w.scene.objects[index];
  const TexPlane& t = *o.as<TexPlane>();
  const auto c = corners(t.plane, t.window);
  const glm::dvec3 a = PovWriter::flip(c[1] - c[0]), b = PovWriter::flip(c[3] - c[0]),
                   p = PovWriter::flip(c[0]);
  const glm::dvec3 n = glm::cross(a, b);
  pov_polygon(w, t.plane, t.window);
  w.out << " texture { M" << o.material << " } texture { pigment { image_map { "
        << PovWriter::image_file(w.scene.textures[t.texture].path) << " once } matrix <" << w.num(a.x)
        << ", " << w.num(a.y) << ", " << w.num(a.z) << ", " << w.num(b.x) << ", " << w.num(b.y)
        << ", " << w.num(b.z) << ", " << w.num(n.x) << ", " << w.num(n.y) << ", " << w.num(n.z)
        << ", " << w.num(p.x) << ", " << w.num(p.y) << ", " << w.num(p.z)
        << "> } finish { ambient 0 diffuse 1 } } }\n";
}

}  // namespace

const EntityHooks kPlane{{EntityKind::plane, "plane", false, kPlaneAttrs, EntityRole::object,
                          "an infinite plane", true},
                         build_plane, pov_plane};
const EntityHooks kFinitePlane{{EntityKind::fplane, "fplane", false, kFinitePlaneAttrs,
                                EntityRole::object,
                                "a rectangle of a plane: xdir's part in the plane is its x axis"},
                               build_fplane, pov_fplane};
const EntityHooks kTiledPlane{{EntityKind::tiled_plane, "tiled_plane", false, kTiledPlaneAttrs,
                               EntityRole::object,
                               "a plane of squares alternating between material and altmaterial"},
                              build_tiled, pov_tiled};
const EntityHooks kTexPlane{{EntityKind::texplane, "texplane", false, kTexPlaneAttrs,
                             EntityRole::object,
                             "a rectangle of a plane with an image on it (mode 0 stretched, "
                             "mode 1 tiled)"},
                            build_texplane, pov_texplane};

}  // namespace rayfarm::entities
