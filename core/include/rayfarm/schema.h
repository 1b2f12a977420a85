// The one table of the scene format: entities, their attributes, value kinds, limits and
// defaults. Parsers, validation, the JSON/model/POV writers and error messages all read it.
#pragma once

#include <array>
#include <span>
#include <string_view>

#include "rayfarm/scene_desc.h"

namespace rayfarm {

enum class ValueKind {
  pixel_dims,    // 2 integers >= 1
  window_dims,   // 2 numbers > 0
  point,         // 3 numbers
  colour,        // 3 numbers >= 0, or 1 meaning all three
  positive,      // 1 number > 0
  direction,     // 3 numbers, not all 0
  material_ref,  // a material name
};

struct AttrSpec {
  std::string_view key;
  ValueKind kind;
  bool required;
  std::array<double, 3> fallback;  // default when not required
};

struct EntitySpec {
  EntityKind kind;
  std::string_view keyword;
  bool name_required;
  std::span<const AttrSpec> attrs;
};

const EntitySpec& entity_spec(EntityKind kind);
const EntitySpec* find_entity(std::string_view keyword);
const AttrSpec* find_attr(const EntitySpec& entity, std::string_view key);
std::span<const std::string_view> entity_keywords();

// How many numbers a value kind takes: {min, max}; {0, 0} for names.
std::array<int, 2> value_count(ValueKind kind);
std::string_view describe(ValueKind kind);  // "2 integers >= 1", ... for messages

// Whether n values make a complete value of this kind (a colour is 1 or 3 numbers, not 2).
bool valid_value_count(ValueKind kind, int n);

// What is wrong with one number of a value of this kind ("must be > 0", ...); empty when it
// is in range. A direction's other rule (not all zero) is is_zero_vector.
std::string_view value_problem(ValueKind kind, double v);
inline bool is_zero_vector(const double* v) { return v[0] == 0 && v[1] == 0 && v[2] == 0; }

// Names as the format allows them: [A-Za-z_][A-Za-z0-9_.-]*
bool is_valid_name(std::string_view name);

constexpr int kMaxNameLength = 256;

}  // namespace rayfarm
