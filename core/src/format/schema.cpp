// Lookups in the scene format's table (the rows are in scene/entities/, collected by
// scene/registry.cpp) and the value kinds' rules.
#include "rayfarm/schema.h"

#include <cmath>
#include <string>
#include <vector>

#include "util/utf8.h"

namespace rayfarm {
namespace {

using V = ValueKind;

// Keyword lists derived from the registry once.
struct Keywords {
  std::vector<std::string_view> all;
  std::vector<std::string_view> by_role[5];
  std::string list;
  Keywords() {
    for (int k = 0; k < kEntityKinds; ++k) {
      const EntitySpec& spec = entity_spec(static_cast<EntityKind>(k));
      all.push_back(spec.keyword);
      by_role[static_cast<int>(spec.role)].push_back(spec.keyword);
      list += (list.empty() ? "" : ", ") + std::string(spec.keyword);
    }
  }
};

const Keywords& keywords() {
  static const Keywords k;
  return k;
}

}  // namespace

const EntitySpec* find_entity(std::string_view keyword) {
  // Every word of a model file that could start an entity is looked up: compare lengths
  // and first letters before the rest.
  static const auto table = [] {
    std::array<std::pair<std::string_view, const EntitySpec*>, kEntityKinds> t{};
    for (int k = 0; k < kEntityKinds; ++k) {
      const EntitySpec& spec = entity_spec(static_cast<EntityKind>(k));
      t[k] = {spec.keyword, &spec};
    }
    return t;
  }();
  if (keyword.empty()) return nullptr;
  for (const auto& [word, spec] : table)
    if (word.size() == keyword.size() && word[0] == keyword[0] && word == keyword) return spec;
  return nullptr;
}

const AttrSpec* find_attr(const EntitySpec& entity, std::string_view key) {
  for (const AttrSpec& a : entity.attrs)
    if (a.key == key) return &a;
  return nullptr;
}

std::span<const std::string_view> entity_keywords() { return keywords().all; }
std::string_view entity_keyword_list() { return keywords().list; }
std::span<const std::string_view> keywords_of(EntityRole role) {
  return keywords().by_role[static_cast<int>(role)];
}

std::string_view unsupported_entity(std::string_view keyword) {
  if (keyword == "pplane")
    return "'pplane' is not supported: the course named it (a plane with an integer shader) but "
           "never defined its attributes or how it looks; use plane, tiled_plane or texplane";
  return {};
}

std::array<int, 2> value_count(ValueKind kind) {
  switch (kind) {
    case V::pixel_dims:
    case V::window_dims: return {2, 2};
    case V::point:
    case V::position:
    case V::direction: return {3, 3};
    case V::colour: return {1, 3};
    case V::positive:
    case V::nonnegative:
    case V::fraction:
    case V::angle:
    case V::integer: return {1, 1};
    case V::material_ref:
    case V::word: return {0, 0};
  }
  return {0, 0};
}

bool valid_value_count(ValueKind kind, int n) {
  auto [lo, hi] = value_count(kind);
  if (kind == V::colour && n == 2) return false;
  return n >= lo && n <= hi;
}

bool is_word_kind(ValueKind kind) { return kind == V::material_ref || kind == V::word; }

bool value_in_range(const AttrSpec& attr, double v) {
  if (!std::isfinite(v)) return false;
  switch (attr.kind) {
    case V::pixel_dims: return v >= 1 && v <= 65535 && v == std::floor(v);
    case V::window_dims: return v >= kMinWindow && v <= kMaxLength;
    case V::positive: return v > 0 && v <= kMaxLength;
    case V::position: return std::abs(v) <= kMaxLength;
    case V::colour:
    case V::nonnegative: return v >= 0;
    case V::fraction: return v >= 0 && v <= 1;
    case V::angle: return v > 0 && v < 180;
    case V::integer: return v == std::floor(v) && v >= attr.lo && v <= attr.hi;
    default: return true;
  }
}

std::string value_problem(const AttrSpec& attr, double v) {
  if (!std::isfinite(v)) return "must be a finite number";
  switch (attr.kind) {
    case V::pixel_dims:
      if (v < 1 || v > 65535 || v != std::floor(v)) return "values must be integers from 1 to 65535";
      break;
    case V::window_dims:
      if (!(v > 0)) return "values must be > 0";
      if (v < kMinWindow || v > kMaxLength)
        return "values must be from 1e-150 to 1e150 (their squares must fit a double)";
      break;
    case V::colour:
      if (v < 0) return "values must be >= 0";
      break;
    case V::positive:
      if (!(v > 0)) return "must be > 0";
      if (v > kMaxLength) return "must be at most 1e150 (its square must fit a double)";
      break;
    case V::position:
      if (std::abs(v) > kMaxLength)
        return "coordinates must be within ±1e150 (the squares of distances must fit a double)";
      break;
    case V::nonnegative:
      if (v < 0) return "must be >= 0";
      break;
    case V::fraction:
      if (!(v >= 0 && v <= 1)) return "must be from 0 to 1";
      break;
    case V::angle:
      if (!(v > 0 && v < 180)) return "must be an angle in degrees above 0 and below 180";
      break;
    case V::integer:
      if (v != std::floor(v) || v < attr.lo || v > attr.hi)
        return attr.lo == attr.hi ? "must be " + std::to_string(attr.lo)
                                  : "must be an integer from " + std::to_string(attr.lo) + " to " +
                                        std::to_string(attr.hi);
      break;
    default:
      break;
  }
  return {};
}

std::string describe(const AttrSpec& attr) {
  switch (attr.kind) {
    case V::pixel_dims: return "2 integers >= 1";
    case V::window_dims: return "2 numbers > 0";
    case V::point: return "3 numbers";
    case V::position: return "3 numbers";  // the range is said when a value is out of it
    case V::direction: return "3 numbers, not all 0";
    case V::colour: return "3 numbers >= 0, or 1 number for all three";
    case V::positive: return "1 number > 0";
    case V::nonnegative: return "1 number >= 0";
    case V::fraction: return "1 number from 0 to 1";
    case V::angle: return "1 angle in degrees";
    case V::integer:
      return attr.lo == attr.hi ? "the integer " + std::to_string(attr.lo)
                                : "1 integer from " + std::to_string(attr.lo) + " to " +
                                      std::to_string(attr.hi);
    case V::material_ref: return "a material name";
    case V::word: return "a texture name or file path";
  }
  return "";
}

bool is_valid_name(std::string_view name) {
  if (name.empty() || name.size() > static_cast<size_t>(kMaxNameLength)) return false;
  auto alpha = [](char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; };
  auto digit = [](char c) { return c >= '0' && c <= '9'; };
  if (!alpha(name[0])) return false;
  for (char c : name.substr(1))
    if (!alpha(c) && !digit(c) && c != '.' && c != '-') return false;
  return true;
}

bool is_valid_path(std::string_view path) {
  if (path.empty() || path.size() > static_cast<size_t>(kMaxPathLength)) return false;
  // What the model file could not write back as one word: space, braces, comment starts,
  // and the separators of <x,y,z>.
  for (char c : path)
    if (static_cast<unsigned char>(c) <= 0x20 || c == 0x7f || c == '{' || c == '}' || c == '#' ||
        c == ',' || c == '<' || c == '>')
      return false;
  // JSON scenes, error bodies and terminals carry text: a name that is not UTF-8 has no form.
  return path.find("//") == std::string_view::npos && is_valid_utf8(path);
}

Where AttrDesc::value_at(size_t i) const {
  if (i >= value_where.size()) return where;
  switch (value_where.json_mode()) {
    case 1: return where;
    case 2: return {0, 0, where.path + "/" + std::to_string(i)};
    default: return value_where[i];
  }
}

void mark_all_invalid(EntityDesc& e) {
  for (const AttrSpec& a : entity_spec(e.kind).attrs) e.invalid_keys.emplace_back(a.key);
}

const AttrDesc* EntityDesc::find(std::string_view key) const {
  for (const AttrDesc& a : attrs)
    if (a.key == key) return &a;
  return nullptr;
}

}  // namespace rayfarm
