// The entity kinds: for each keyword its schema row and the function that builds it into a
// Scene. Adding a kind is its file in scene/entities/ and one line in registry.cpp (plus its
// geometry in geometry/ when it is an object).
#pragma once

#include <string>

#include "format/pov_writer.h"
#include "rayfarm/scene.h"
#include "rayfarm/schema.h"
#include "scene/entity_reader.h"

namespace rayfarm {

struct EntityHooks {
  EntitySpec spec;
  // Reads the checked attributes and appends the entity to the scene (or reports why not).
  void (*build)(EntityReader& reader, Scene& scene);
  // Writes the entity (an object or a light, by its index in the scene) as POV-Ray SDL, for
  // timing comparisons (write_pov); null for kinds that are only referred to.
  void (*pov)(PovWriter& writer, int index) = nullptr;
};

const EntityHooks& entity_hooks(EntityKind kind);
EntityKind kind_of(const Light& light);

// The entity files' tables (scene/entities/*.cpp).
namespace entities {
extern const EntityHooks kCamera, kMaterial, kTexture, kLight, kSpotlight, kProjector, kSphere,
    kPlane, kFinitePlane, kTiledPlane, kTexPlane, kTriangle, kTri, kRevsurf;
}

}  // namespace rayfarm
