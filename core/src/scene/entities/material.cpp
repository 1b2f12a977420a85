// material NAME { ambient  diffuse  specular  shininess  transparency }
#include "scene/registry.h"

namespace rayfarm::entities {
namespace {

using V = ValueKind;
constexpr AttrSpec kAttrs[] = {
    {"ambient", V::colour, false},
    {"diffuse", V::colour, false},
    {"specular", V::colour, false},
    {"shininess", V::nonnegative, false},
    {"transparency", V::fraction, false},
};

void build(EntityReader& r, Scene& scene) {
  auto ka = r.vec3("ambient"), kd = r.vec3("diffuse"), ks = r.vec3("specular");
  // The default depends on the profile (scene.h), so an absent shininess stays absent.
  std::optional<double> n;
  if (r.has("shininess")) {
    n = r.number("shininess");
    if (!n) return;
  }
  auto t = r.number("transparency");
  if (!ka || !kd || !ks || !t) return;
  const EntityDesc& e = r.entity();
  scene.materials.push_back({e.name, e.where, *ka, *kd, *ks, n, *t});
}

}  // namespace

const EntityHooks kMaterial{{EntityKind::material, "material", true, kAttrs,
                             EntityRole::material, "surface colours and reflectance", true},
                            build};

}  // namespace rayfarm::entities
