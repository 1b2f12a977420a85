// sphere NAME { material M  center x y z  radius r }
#include "scene/registry.h"

namespace rayfarm::entities {
namespace {

using V = ValueKind;
constexpr AttrSpec kAttrs[] = {
    {"material", V::material_ref, true},
    {"center", V::position, true},
    {"radius", V::positive, true},
};

void build(EntityReader& r, Scene& scene) {
  auto c = r.vec3("center");
  auto radius = r.number("radius");
  auto m = r.material("material");
  if (!c || !radius || !m) return;
  scene.objects.push_back(r.object(*m, Sphere{*c, *radius}));
}

void pov(PovWriter& w, int index) {
  const Object& o = w.scene.objects[index];
  const Sphere& s = *o.as<Sphere>();
  w.out << "sphere { " << w.at(s.center) << ", " << w.num(s.radius) << " " << w.texture(o.material)
        << " }\n";
}

}  // namespace

const EntityHooks kSphere{{EntityKind::sphere, "sphere", false, kAttrs, EntityRole::object,
                           "a sphere", true},
                          build, pov};

}  // namespace rayfarm::entities
