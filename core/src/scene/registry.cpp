// The registry of entity kinds, in EntityKind order.
#include "scene/registry.h"

namespace rayfarm {
namespace {

constexpr const EntityHooks* kKinds[] = {
    &entities::kCamera,    &entities::kMaterial,    &entities::kTexture,
    &entities::kLight,     &entities::kSpotlight,   &entities::kProjector,
    &entities::kSphere,    &entities::kPlane,       &entities::kFinitePlane,
    &entities::kTiledPlane, &entities::kTexPlane,   &entities::kTriangle,
    &entities::kTri,       &entities::kRevsurf,
};
static_assert(std::size(kKinds) == kEntityKinds);

}  // namespace

const EntityHooks& entity_hooks(EntityKind kind) {
  const EntityHooks& h = *kKinds[static_cast<int>(kind)];
  return h;
}

const EntitySpec& entity_spec(EntityKind kind) { return entity_hooks(kind).spec; }

EntityKind kind_of(const Light& light) {
  switch (light.kind) {
    case LightKind::spot: return EntityKind::spotlight;
    case LightKind::projector: return EntityKind::projector;
    default: return EntityKind::light;
  }
}

}  // namespace rayfarm
