// triangle (with or without its plane) and the 2009 course's tri (v0 v1 v2).
#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "scene/entities/plane_parts.h"

namespace rayfarm::entities {
namespace {

using V = ValueKind;
constexpr AttrSpec kTriangleAttrs[] = {
    {"material", V::material_ref, true},
    {"normal", V::direction, false},
    {"point", V::point, false},
    {"vertex1", V::position, true},
    {"vertex2", V::position, true},
    {"vertex3", V::position, true},
};
constexpr AttrSpec kTriAttrs[] = {
    {"material", V::material_ref, true},
    {"v0", V::position, true},
    {"v1", V::position, true},
    {"v2", V::position, true},
};

// Whether the triangle has an area: in its own plane, or projected into the given one.
bool has_area(const Triangle& t) {
  glm::dvec3 e1 = t.vertex[1] - t.vertex[0], e2 = t.vertex[2] - t.vertex[0];
  // At a scale near 1 first: the test is a ratio, and at 1e154 or 1e-100 the products below
  // would overflow or underflow and call any triangle a line.
  const double most = std::max({std::abs(e1.x), std::abs(e1.y), std::abs(e1.z), std::abs(e2.x),
                                std::abs(e2.y), std::abs(e2.z)});
  if (most > 0 && std::isfinite(most)) {
    e1 /= most;
    e2 /= most;
  }
  glm::dvec3 c = glm::cross(e1, e2);
  if (t.plane) c = glm::dot(c, unit_direction(t.plane->normal)) * unit_direction(t.plane->normal);
  const double scale = glm::length(e1) * glm::length(e2);
  return glm::length(c) > 1e-12 * scale && scale > 0;
}

void finish(EntityReader& r, Scene& scene, int material, const Triangle& t) {
  if (!has_area(t)) {
    r.error_at_entity("degenerate", r.describe() + " has no area: its vertices are on one line" +
                                        (t.plane ? " as seen along its normal" : ""));
    return;
  }
  scene.objects.push_back(r.object(material, t));
}

void build_triangle(EntityReader& r, Scene& scene) {
  auto m = r.material("material");
  auto a = r.vec3("vertex1"), b = r.vec3("vertex2"), c = r.vec3("vertex3");
  Triangle t;
  if (r.has("normal") || r.has("point")) {
    for (std::string_view key : {"normal", "point"})
      if (!r.has(key)) {
        r.error_at_entity("missing-attribute",
                          r.describe() + " is missing '" + std::string(key) +
                              "': a triangle gives both its plane's normal and point, or neither");
        return;
      }
    auto plane = read_plane(r);
    if (!plane) return;
    t.plane = *plane;
  }
  if (!m || !a || !b || !c) return;
  t.vertex = {*a, *b, *c};
  finish(r, scene, *m, t);
}

void build_tri(EntityReader& r, Scene& scene) {
  auto m = r.material("material");
  auto a = r.vec3("v0"), b = r.vec3("v1"), c = r.vec3("v2");
  if (!m || !a || !b || !c) return;
  finish(r, scene, *m, Triangle{{*a, *b, *c}, std::nullopt});
}

// The vertices as drawn: projected along the normal into the triangle's plane, if it has one.
void pov(PovWriter& w, int index) {
  const Object& o = w.scene.objects[index];
  const Triangle& t = *o.as<Triangle>();
  glm::dvec3 v[3] = {t.vertex[0], t.vertex[1], t.vertex[2]};
  if (t.plane) {
    const glm::dvec3 n = unit_direction(t.plane->normal);
    for (glm::dvec3& p : v) p -= glm::dot(p - t.plane->point, n) * n;
  }
  w.out << "triangle { " << w.at(v[0]) << ", " << w.at(v[1]) << ", " << w.at(v[2]) << " "
        << w.texture(o.material) << " }\n";
}

}  // namespace

const EntityHooks kTriangle{{EntityKind::triangle, "triangle", false, kTriangleAttrs,
                             EntityRole::object,
                             "a triangle (in the plane given by normal and point, if given)"},
                            build_triangle, pov};
const EntityHooks kTri{{EntityKind::tri, "tri", false, kTriAttrs, EntityRole::object,
                        "a triangle (the 2009 course's form)"},
                       build_tri, pov};

}  // namespace rayfarm::entities
