// camera NAME { pixeldim W H  worlddim ww wh  viewpoint x y z }
#include "scene/registry.h"

namespace rayfarm::entities {
namespace {

using V = ValueKind;
constexpr AttrSpec kAttrs[] = {
    {"pixeldim", V::pixel_dims, true},
    {"worlddim", V::window_dims, true},
    {"viewpoint", V::position, true},
};

void build(EntityReader& r, Scene& scene) {
  auto pix = r.pair("pixeldim");
  auto win = r.pair("worlddim");
  auto eye = r.vec3("viewpoint");
  if (!pix || !win || !eye) return;
  const EntityDesc& e = r.entity();
  scene.cameras.push_back({e.name, e.where, static_cast<int>((*pix)[0]),
                           static_cast<int>((*pix)[1]), (*win)[0], (*win)[1], *eye});
}

}  // namespace

const EntityHooks kCamera{{EntityKind::camera, "camera", false, kAttrs, EntityRole::camera,
                           "the eye and the view window on the screen plane z = 0", true},
                          build};

}  // namespace rayfarm::entities
