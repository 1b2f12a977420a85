// revsurf NAME { material M  surfer k  base x y z  direction x y z  height h }: a surface of
// revolution about the axis through base along direction, with the course's profile k.
#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "geometry/frame.h"
#include "scene/registry.h"

namespace rayfarm::entities {
namespace {

using V = ValueKind;
constexpr AttrSpec kAttrs[] = {
    {"material", V::material_ref, true},
    {"surfer", V::integer, true, {0, 0, 0}, 1, 3},
    {"base", V::position, true},
    {"direction", V::direction, true},
    {"height", V::positive, true},
};

void build(EntityReader& r, Scene& scene) {
  auto m = r.material("material");
  auto surfer = r.integer("surfer");
  auto base = r.vec3("base"), dir = r.vec3("direction");
  auto h = r.number("height");
  if (!m || !surfer || !base || !dir || !h) return;
  scene.objects.push_back(r.object(*m, Revsurf{*surfer, *base, *dir, *h}));
}

// POV-Ray's surface of revolution (sor) about its y axis, through points of the profile,
// turned onto the axis; open at both ends as the course's surfaces are.
void pov(PovWriter& w, int index) {
  const Object& o = w.scene.objects[index];
  const Revsurf& r = *o.as<Revsurf>();
  constexpr int kPoints = 64;
  auto radius = [&](double y) {
    switch (r.surfer) {
      case 1: return std::max(4 - 2.0 / 3 * y, 1e-6);
      case 2: return 1 + 0.5 * std::cos(y);
      default: return 1 + 0.5 * std::sin(y);
    }
  };
  w.out << "sor { " << kPoints + 2;
  for (int i = -1; i <= kPoints; ++i) {
    const double y = r.height * i / (kPoints - 1);
    w.out << ", <" << w.num(radius(std::clamp(y, 0.0, r.height))) << ", " << w.num(y) << ">";
  }
  const glm::dvec3 a = unit_direction(PovWriter::flip(r.direction));
  // A frame whose y axis is the surface's axis.
  const glm::dvec3 helper = std::abs(a.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 0, 1);
  const glm::dvec3 x = glm::normalize(glm::cross(helper, a)), z = glm::cross(x, a);
  const glm::dvec3 b = PovWriter::flip(r.base);
  w.out << " open " << w.texture(o.material) << " matrix <" << w.num(x.x) << ", " << w.num(x.y)
        << ", " << w.num(x.z) << ", " << w.num(a.x) << ", " << w.num(a.y) << ", " << w.num(a.z)
        << ", " << w.num(z.x) << ", " << w.num(z.y) << ", " << w.num(z.z) << ", " << w.num(b.x)
        << ", " << w.num(b.y) << ", " << w.num(b.z) << "> }\n";
}

}  // namespace

const EntityHooks kRevsurf{{EntityKind::revsurf, "revsurf", false, kAttrs, EntityRole::object,
                            "a surface of revolution: surfer 1 a cone, 2 and 3 waves"},
                           build, pov};

}  // namespace rayfarm::entities
