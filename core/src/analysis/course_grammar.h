// The entities and attributes of the course's reference program (CPSC 102, 2014–18), as its
// parse tables had them: attribute groups read in order, each value read by one scanf.
#pragma once

#include <span>
#include <string_view>

namespace rayfarm::course {

// How the program reads one value.
enum class Value {
  real,      // %lf
  integer,   // %d
  material,  // %s, a material defined earlier; names live in 32-byte buffers
  texture,   // %s, a texture defined earlier or an image file's path; a 64-byte buffer
  path,      // %s, an image file's path
};

struct Attr {
  std::string_view name;
  int count = 1;  // values
  Value value = Value::real;
  bool required = true;
  std::string_view note = {};  // added to a wrong-value-count warning
};

// A group is one call of the course's parser(). Every group but an entity's last reads exactly
// as many attributes as it has; the last reads up to '}'. Inside a group the order is free.
using Group = std::span<const Attr>;

struct Entity {
  std::string_view keyword;
  std::span<const Group> groups;
  bool object = false;  // reads `material NAME` before its groups (the course's object_t)
};

constexpr size_t kMaxGroups = 4;
constexpr size_t kMaxGroupSize = 5;
constexpr size_t kNameMax = 31;     // NAME_LEN 32 in the course's ray.h, with the NUL
constexpr size_t kTexnameMax = 63;  // texplane_t::texname[64]

const Entity* find_entity(std::string_view keyword);
std::span<const Entity> entities();
std::span<const std::string_view> entity_keywords();

// Where `name` sits in `entity`: group and index, or {-1, -1}.
struct AttrRef {
  int group = -1;
  int index = -1;
  explicit operator bool() const { return group >= 0; }
};
AttrRef find_attr(const Entity& entity, std::string_view name);

}  // namespace rayfarm::course
