// The table of the scene format: entities, their attributes, value kinds, limits, defaults
// and where they live in JSON. The model-file and JSON parsers, the builder, both writers and
// every message that lists keywords read it; each kind's row is in its own file
// (core/src/scene/entities/), collected by the registry (core/src/scene/registry.cpp).
#pragma once

#include <array>
#include <span>
#include <string_view>

#include "rayfarm/scene_desc.h"

namespace rayfarm {

enum class ValueKind {
  pixel_dims,    // 2 integers >= 1
  window_dims,   // 2 numbers from kMinWindow to kMaxLength
  point,         // 3 numbers
  position,      // 3 numbers within ±kMaxLength: where distances are measured from (an eye,
                 // a light, a sphere's centre, a revsurf's base), squared
  colour,        // 3 numbers >= 0, or 1 meaning all three
  positive,      // 1 number > 0 and at most kMaxLength (a radius, a height)
  nonnegative,   // 1 number >= 0
  fraction,      // 1 number in [0, 1]
  angle,         // 1 number of degrees in (0, 180)
  integer,       // 1 integer in [AttrSpec::lo, AttrSpec::hi]
  direction,     // 3 numbers, not all 0
  material_ref,  // a material name
  word,          // a texture name or a file path: any word
};

// The largest radius or height, and |coordinate| of a position: its square, which the hit
// tests and the lengths of rays compute, must fit a double (a sphere of radius 1e160 would
// vanish rather than fill the view, an eye at 1e155 would see nothing).
inline constexpr double kMaxLength = 1e150;
// The least size of a window (a camera's worlddim, a finite plane's dimensions, a tile): its
// square must be a normal double too. A camera 8e-170 wide has pixel rays whose lengths
// square to 0, and renders black where its twin 8 units wide does not.
inline constexpr double kMinWindow = 1e-150;

struct AttrSpec {
  std::string_view key;
  ValueKind kind;
  bool required;
  std::array<double, 3> fallback = {0, 0, 0};  // default when not required and absent
  int lo = 0;  // integer kinds: the accepted range
  int hi = 0;
};

// What an entity is to the scene, which decides its place in JSON: cameras and materials and
// textures are keyed by name, lights and objects are array entries with a "type".
enum class EntityRole { camera, material, texture, light, object };

struct EntitySpec {
  EntityKind kind;
  std::string_view keyword;
  bool name_required;
  std::span<const AttrSpec> attrs;
  EntityRole role;
  std::string_view summary;  // one line for messages and the format's documentation
  bool fast_path = false;    // the model loader's fast path reads it (format/model_fast.cpp)
};

const EntitySpec& entity_spec(EntityKind kind);
// An entity whose body could not be read, or one that stands in for a misspelt keyword or
// key: every attribute counts as written-but-bad, so the scene builder reports none of them
// missing, and its kind and name still count (no "no camera" or "undefined material" besides
// the one error).
void mark_all_invalid(EntityDesc& e);
const EntitySpec* find_entity(std::string_view keyword);
const AttrSpec* find_attr(const EntitySpec& entity, std::string_view key);
std::span<const std::string_view> entity_keywords();
// "camera, material, ..., revsurf" for messages.
std::string_view entity_keyword_list();
// The keywords of entities of one role, in table order.
std::span<const std::string_view> keywords_of(EntityRole role);

// A word some course material uses as an entity but that the format does not accept, with
// the reason to give; empty when `keyword` is not one.
std::string_view unsupported_entity(std::string_view keyword);

// How many numbers a value kind takes: {min, max}; {0, 0} for words and names.
std::array<int, 2> value_count(ValueKind kind);
std::string describe(const AttrSpec& attr);  // "2 integers >= 1", ... for messages
bool is_word_kind(ValueKind kind);           // material_ref or word: one word, no numbers

// Whether n values make a complete value of this kind (a colour is 1 or 3 numbers, not 2).
bool valid_value_count(ValueKind kind, int n);

// What is wrong with one number of a value of this attribute ("must be > 0", ...); empty when
// it is in range. A direction's other rule (not all zero) is is_zero_vector.
std::string value_problem(const AttrSpec& attr, double v);
// Whether value_problem would find nothing, without building its message (the loader's
// fast path asks this of every number).
bool value_in_range(const AttrSpec& attr, double v);
inline bool is_zero_vector(const double* v) { return v[0] == 0 && v[1] == 0 && v[2] == 0; }

// Names as the format allows them: [A-Za-z_][A-Za-z0-9_.-]*
bool is_valid_name(std::string_view name);

constexpr int kMaxNameLength = 256;
// File paths of textures: at most this long; one word of the model file (no white space,
// braces, comment starts or vector separators).
constexpr int kMaxPathLength = 1024;
bool is_valid_path(std::string_view path);

}  // namespace rayfarm
