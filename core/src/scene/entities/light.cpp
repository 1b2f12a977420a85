// light, spotlight and projector: a point light, one with a cone, one behind a slide.
#include <cmath>

#include <glm/geometric.hpp>

#include "scene/entities/plane_parts.h"

namespace rayfarm::entities {
namespace {

using V = ValueKind;
constexpr AttrSpec kLightAttrs[] = {
    {"location", V::position, true},
    {"emissivity", V::colour, false, {1, 1, 1}},
};
constexpr AttrSpec kSpotAttrs[] = {
    {"location", V::position, true},
    {"emissivity", V::colour, false, {1, 1, 1}},
    {"point", V::point, true},
    {"theta", V::angle, true},
};
constexpr AttrSpec kProjectorAttrs[] = {
    {"location", V::position, true},
    {"emissivity", V::colour, false, {1, 1, 1}},
    {"point", V::point, true},
    {"normal", V::direction, true},
    {"xdir", V::direction, true},
    {"dimensions", V::window_dims, true},
    {"texname", V::word, true},
    {"mode", V::integer, false, {0, 0, 0}, 0, 0},
};

// The common part: location and emissivity; nullopt when either was wrong.
std::optional<Light> base(EntityReader& r, LightKind kind) {
  auto loc = r.vec3("location"), em = r.vec3("emissivity");
  if (!loc || !em) return std::nullopt;
  Light l;
  l.name = r.entity().name;
  l.where = r.entity().where;
  l.kind = kind;
  l.location = *loc;
  l.emissivity = *em;
  return l;
}

void build_light(EntityReader& r, Scene& scene) {
  if (auto l = base(r, LightKind::point)) scene.lights.push_back(std::move(*l));
}

void build_spot(EntityReader& r, Scene& scene) {
  auto l = base(r, LightKind::spot);
  auto aim = r.vec3("point");
  auto theta = r.number("theta");
  if (!l || !aim || !theta) return;
  if (*aim == l->location) {
    r.error("out-of-range", "'point' must differ from 'location': it sets the spotlight's direction",
            r.find("point")->where);
    return;
  }
  l->aim = *aim;
  l->theta = *theta;
  scene.lights.push_back(std::move(*l));
}

// The slide is a window of a plane, read as a finite plane's.
void build_projector(EntityReader& r, Scene& scene) {
  auto l = base(r, LightKind::projector);
  auto plane = read_plane(r);
  auto texture = r.texture("texname");
  auto mode = r.integer("mode");
  auto window = read_window(r, plane);
  if (!l || !plane || !texture || !mode || !window) return;
  l->point = plane->point;
  l->normal = plane->normal;
  l->window = *window;
  l->texture = *texture;
  l->mode = *mode;
  scene.lights.push_back(std::move(*l));
}

// POV-Ray's lights fade as 1/(1 + d) here against the course's 1/d (write_pov's note).
void pov_light_source(PovWriter& w, const Light& l) {
  w.out << "light_source { " << w.at(l.location) << " color rgb " << w.vec(l.emissivity)
        << " fade_distance 1 fade_power 1" << (w.options.shadows ? "" : " shadowless");
}

void pov_light(PovWriter& w, int index) {
  pov_light_source(w, w.scene.lights[index]);
  w.out << " }\n";
}

void pov_spot(PovWriter& w, int index) {
  const Light& l = w.scene.lights[index];
  pov_light_source(w, l);
  w.out << " spotlight point_at " << w.at(l.aim) << " radius " << w.num(l.theta) << " falloff "
        << w.num(l.theta) << " tightness 0 }\n";
}

// POV-Ray cannot filter a light by an image: the slide's window is kept, as a light projected
// through a rectangle.
void pov_projector(PovWriter& w, int index) {
  const Light& l = w.scene.lights[index];
  const PlaneFrame f = *plane_frame(l.normal, l.window.xdir);  // checked when built
  const glm::dvec3 u = f.u, v = f.v, p = l.point;
  const glm::dvec3 c[4] = {p, p + l.window.width * u, p + l.window.width * u + l.window.height * v,
                           p + l.window.height * v};
  pov_light_source(w, l);
  w.out << " projected_through { polygon { 5, " << w.at(c[0]) << ", " << w.at(c[1]) << ", "
        << w.at(c[2]) << ", " << w.at(c[3]) << ", " << w.at(c[0]) << " } } }\n";
}

}  // namespace

const EntityHooks kLight{{EntityKind::light, "light", false, kLightAttrs, EntityRole::light,
                          "a point light", true},
                         build_light, pov_light};
const EntityHooks kSpotlight{{EntityKind::spotlight, "spotlight", false, kSpotAttrs,
                              EntityRole::light,
                              "a point light that lights only within theta degrees of the "
                              "direction towards point"},
                             build_spot, pov_spot};
const EntityHooks kProjector{{EntityKind::projector, "projector", false, kProjectorAttrs,
                              EntityRole::light,
                              "a point light seen through a slide (a texture on a window)"},
                             build_projector, pov_projector};

}  // namespace rayfarm::entities
