// texture NAME { filename PATH }: a PPM image for texplanes and projectors, by name.
#include "scene/registry.h"

namespace rayfarm::entities {
namespace {

constexpr AttrSpec kAttrs[] = {
    {"filename", ValueKind::word, true},
};

// The builder registers textures before objects and lights refer to them
// (SceneBuilder::add_texture); nothing is left to do here.
void build(EntityReader&, Scene&) {}

}  // namespace

const EntityHooks kTexture{{EntityKind::texture, "texture", true, kAttrs, EntityRole::texture,
                            "a PPM image file (P6 or P3), relative to the model file"},
                           build};

}  // namespace rayfarm::entities
