// The reference program's parse tables (docs/profiles.md §4–5; the course's given model.c,
// object.c, parser.c, material.cpp and ray.h, as they survive in students' repositories).
#include "analysis/course_grammar.h"

namespace rayfarm::course {
namespace {

using V = Value;

constexpr Attr kCameraAttrs[] = {{"pixeldim", 2, V::integer}, {"worlddim", 2}, {"viewpoint", 3}};
// All optional (the logs print 0.0 for what a file leaves out), but material.cpp asserts that
// at least one was read.
constexpr Attr kMaterialAttrs[] = {
    {"ambient", 3, V::real, false},
    {"diffuse", 3, V::real, false},
    {"specular", 1, V::real, false, "three numbers were the 2009 program's form"},
    {"shininess", 1, V::real, false},
    {"transparency", 1, V::real, false}};
constexpr Attr kTextureAttrs[] = {{"filename", 1, V::path}};
constexpr Attr kLightAttrs[] = {{"location", 3}, {"emissivity", 3}};
constexpr Attr kSpotAttrs[] = {{"point", 3}, {"theta", 1}};
constexpr Attr kPlaneAttrs[] = {{"normal", 3}, {"point", 3}};
constexpr Attr kFiniteAttrs[] = {{"xdir", 3}, {"dimensions", 2}};
// tiled_plane is a plane with its own group, not an fplane's (the course's ray.h derives
// tplane_t from plane_t): shiny2 and shiny3, which the program read, give dimensions,
// altmaterial, xdir in that order.
constexpr Attr kTiledAttrs[] = {{"xdir", 3}, {"dimensions", 2}, {"altmaterial", 1, V::material}};
constexpr Attr kTexAttrs[] = {{"texname", 1, V::texture}, {"mode", 1, V::integer}};
constexpr Attr kSphereAttrs[] = {{"center", 3}, {"radius", 1}};
// No reference log or image exists for triangle (docs/profiles.md §11): one group in free order, the
// two forms of §5 (with or without normal and point) both accepted.
constexpr Attr kTriangleAttrs[] = {{"normal", 3, V::real, false},
                                   {"point", 3, V::real, false},
                                   {"vertex1", 3},
                                   {"vertex2", 3},
                                   {"vertex3", 3}};
constexpr Attr kRevsurfAttrs[] = {
    {"surfer", 1, V::integer}, {"base", 3}, {"direction", 3}, {"height", 1}};

constexpr Group kCamera[] = {kCameraAttrs};
constexpr Group kMaterial[] = {kMaterialAttrs};
constexpr Group kTexture[] = {kTextureAttrs};
constexpr Group kLight[] = {kLightAttrs};
constexpr Group kSpotlight[] = {kLightAttrs, kSpotAttrs};
// A light, then a texplane without an object header (the program's projector_t).
constexpr Group kProjector[] = {kLightAttrs, kPlaneAttrs, kFiniteAttrs, kTexAttrs};
constexpr Group kSphere[] = {kSphereAttrs};
constexpr Group kPlane[] = {kPlaneAttrs};
constexpr Group kFplane[] = {kPlaneAttrs, kFiniteAttrs};
constexpr Group kTiledPlane[] = {kPlaneAttrs, kTiledAttrs};
constexpr Group kTexplane[] = {kPlaneAttrs, kFiniteAttrs, kTexAttrs};
constexpr Group kTriangle[] = {kTriangleAttrs};
constexpr Group kRevsurf[] = {kRevsurfAttrs};

constexpr Entity kEntities[] = {
    {"camera", kCamera},           {"material", kMaterial},
    {"texture", kTexture},         {"light", kLight},
    {"spotlight", kSpotlight},     {"projector", kProjector},
    {"sphere", kSphere, true},     {"plane", kPlane, true},
    {"fplane", kFplane, true},     {"tiled_plane", kTiledPlane, true},
    {"texplane", kTexplane, true}, {"triangle", kTriangle, true},
    {"revsurf", kRevsurf, true},
};

constexpr std::string_view kKeywords[] = {
    "camera", "material", "texture",     "light",    "spotlight", "projector", "sphere",
    "plane",  "fplane",   "tiled_plane", "texplane", "triangle",  "revsurf"};
static_assert(std::size(kKeywords) == std::size(kEntities));

}  // namespace

std::span<const Entity> entities() { return kEntities; }
std::span<const std::string_view> entity_keywords() { return kKeywords; }

const Entity* find_entity(std::string_view keyword) {
  for (const Entity& e : kEntities)
    if (e.keyword == keyword) return &e;
  return nullptr;
}

AttrRef find_attr(const Entity& entity, std::string_view name) {
  for (size_t g = 0; g < entity.groups.size(); ++g)
    for (size_t i = 0; i < entity.groups[g].size(); ++i)
      if (entity.groups[g][i].name == name) return {static_cast<int>(g), static_cast<int>(i)};
  return {};
}

}  // namespace rayfarm::course
