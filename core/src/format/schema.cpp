// The entity/attribute table of the scene format (SPEC §1).
#include "rayfarm/schema.h"

#include <cmath>

namespace rayfarm {
namespace {

using V = ValueKind;

constexpr AttrSpec kCamera[] = {
    {"pixeldim", V::pixel_dims, true, {0, 0, 0}},
    {"worlddim", V::window_dims, true, {0, 0, 0}},
    {"viewpoint", V::point, true, {0, 0, 0}},
};
constexpr AttrSpec kMaterial[] = {
    {"ambient", V::colour, false, {0, 0, 0}},
    {"diffuse", V::colour, false, {0, 0, 0}},
    {"specular", V::colour, false, {0, 0, 0}},
    {"shininess", V::positive, false, {32, 0, 0}},
};
constexpr AttrSpec kLight[] = {
    {"location", V::point, true, {0, 0, 0}},
    {"emissivity", V::colour, false, {1, 1, 1}},
};
constexpr AttrSpec kSphere[] = {
    {"material", V::material_ref, true, {0, 0, 0}},
    {"center", V::point, true, {0, 0, 0}},
    {"radius", V::positive, true, {0, 0, 0}},
};
constexpr AttrSpec kPlane[] = {
    {"material", V::material_ref, true, {0, 0, 0}},
    {"normal", V::direction, true, {0, 0, 0}},
    {"point", V::point, true, {0, 0, 0}},
};

constexpr EntitySpec kEntities[] = {
    {EntityKind::camera, "camera", false, kCamera},
    {EntityKind::material, "material", true, kMaterial},
    {EntityKind::light, "light", false, kLight},
    {EntityKind::sphere, "sphere", false, kSphere},
    {EntityKind::plane, "plane", false, kPlane},
};

constexpr std::string_view kKeywords[] = {"camera", "material", "light", "sphere", "plane"};

}  // namespace

const EntitySpec& entity_spec(EntityKind kind) { return kEntities[static_cast<int>(kind)]; }

const EntitySpec* find_entity(std::string_view keyword) {
  for (const EntitySpec& e : kEntities)
    if (e.keyword == keyword) return &e;
  return nullptr;
}

const AttrSpec* find_attr(const EntitySpec& entity, std::string_view key) {
  for (const AttrSpec& a : entity.attrs)
    if (a.key == key) return &a;
  return nullptr;
}

std::span<const std::string_view> entity_keywords() { return kKeywords; }

std::array<int, 2> value_count(ValueKind kind) {
  switch (kind) {
    case V::pixel_dims:
    case V::window_dims: return {2, 2};
    case V::point:
    case V::direction: return {3, 3};
    case V::colour: return {1, 3};
    case V::positive: return {1, 1};
    case V::material_ref: return {0, 0};
  }
  return {0, 0};
}

bool valid_value_count(ValueKind kind, int n) {
  auto [lo, hi] = value_count(kind);
  if (kind == V::colour && n == 2) return false;
  return n >= lo && n <= hi;
}

std::string_view value_problem(ValueKind kind, double v) {
  if (!std::isfinite(v)) return "must be a finite number";
  switch (kind) {
    case V::pixel_dims:
      if (v < 1 || v > 65535 || v != std::floor(v)) return "values must be integers from 1 to 65535";
      break;
    case V::window_dims:
      if (!(v > 0)) return "values must be > 0";
      break;
    case V::colour:
      if (v < 0) return "values must be >= 0";
      break;
    case V::positive:
      if (!(v > 0)) return "must be > 0";
      break;
    default:
      break;
  }
  return {};
}

std::string_view describe(ValueKind kind) {
  switch (kind) {
    case V::pixel_dims: return "2 integers >= 1";
    case V::window_dims: return "2 numbers > 0";
    case V::point: return "3 numbers";
    case V::direction: return "3 numbers, not all 0";
    case V::colour: return "3 numbers >= 0, or 1 number for all three";
    case V::positive: return "1 number > 0";
    case V::material_ref: return "a material name";
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

const AttrDesc* EntityDesc::find(std::string_view key) const {
  for (const AttrDesc& a : attrs)
    if (a.key == key) return &a;
  return nullptr;
}

}  // namespace rayfarm
