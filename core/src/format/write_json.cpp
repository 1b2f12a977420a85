// SceneDesc to the JSON scene format (docs/json-format.md).
#include <charconv>
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <set>

#include "rayfarm/model_parser.h"
#include "rayfarm/schema.h"
#include "rayfarm/writers.h"

namespace rayfarm {
namespace {

using Json = nlohmann::ordered_json;

Json number(double v) {
  // Integral values print as integers ("800", not "800.0"); -0 stays a double to keep its sign.
  if (v == std::floor(v) && std::fabs(v) < 9e15 && !(v == 0 && std::signbit(v)))
    return static_cast<long long>(v);
  return v;
}

Json attr_value(const AttrSpec& spec, const AttrDesc& a) {
  if (is_word_kind(spec.kind)) return a.word;
  if (a.numbers.size() == 1 && value_count(spec.kind)[0] == 1) return number(a.numbers[0]);
  Json arr = Json::array();
  for (double v : a.numbers) arr.push_back(number(v));
  return arr;
}

Json attrs_of(const EntityDesc& e) {
  Json obj = Json::object();
  for (const AttrDesc& a : e.attrs)
    if (const AttrSpec* spec = find_attr(entity_spec(e.kind), a.key))
      obj[a.key] = attr_value(*spec, a);
  return obj;
}

// Option text as the JSON value that reads back to the same text: booleans, integers
// exactly (a 64-bit seed must not pass through a double), numbers, colours as arrays.
Json option_value(const std::string& name, const std::string& text) {
  if (text == "true") return true;
  if (text == "false") return false;
  const char* first = text.data();
  const char* last = text.data() + text.size();
  if (std::uint64_t u = 0;
      !text.empty() && std::from_chars(first, last, u).ptr == last && std::to_string(u) == text)
    return u;
  if (std::int64_t i = 0;
      !text.empty() && std::from_chars(first, last, i).ptr == last && std::to_string(i) == text)
    return i;
  std::vector<double> parts;
  size_t start = 0;
  while (start < text.size()) {
    size_t stop = text.find_first_of(", ", start);
    if (stop == std::string::npos) stop = text.size();
    if (stop > start) {
      auto v = parse_number(std::string_view(text).substr(start, stop - start));
      if (!v) return text;
      parts.push_back(*v);
    }
    start = stop + 1;
  }
  if (parts.empty()) return text;
  if (name == "background") {
    Json arr = Json::array();
    for (double v : parts) arr.push_back(number(v));
    return arr;
  }
  // A number only when it reads back as the same text; otherwise the text itself.
  if (parts.size() == 1 && format_number(parts[0]) == text) return number(parts[0]);
  return text;
}

// Adds a member whose key is new (names of one kind are unique in a valid scene) without
// ordered_json's linear key search, which made 100,000 materials take n²/2 compares.
void append(Json& object, std::string key, Json value) {
  if (object.is_null()) object = Json::object();
  auto& members = static_cast<Json::object_t::Container&>(object.get_ref<Json::object_t&>());
  members.emplace_back(std::move(key), std::move(value));
}

}  // namespace

std::string write_json(const SceneDesc& desc, bool with_render) {
  Json root = Json::object();
  int cameras = 0;
  bool all_named = true;
  for (const EntityDesc& e : desc.entities)
    if (e.kind == EntityKind::camera) {
      ++cameras;
      all_named = all_named && !e.name.empty();
    }
  bool single = cameras == 1 && !all_named;
  // JSON cameras are keyed by name: unnamed ones get the first free "cameraN".
  std::set<std::string> taken;
  for (const EntityDesc& e : desc.entities)
    if (e.kind == EntityKind::camera) taken.insert(e.name);
  int unnamed = 0;
  auto free_name = [&] {
    std::string n;
    do n = "camera" + std::to_string(++unnamed);
    while (!taken.insert(n).second);
    return n;
  };
  for (const EntityDesc& e : desc.entities) {
    const EntitySpec& spec = entity_spec(e.kind);
    switch (spec.role) {
      case EntityRole::camera:
        if (single)
          root["camera"] = attrs_of(e);
        else
          append(root["cameras"], e.name.empty() ? free_name() : e.name, attrs_of(e));
        break;
      case EntityRole::material:
        append(root["materials"], e.name, attrs_of(e));
        break;
      case EntityRole::texture:
        append(root["textures"], e.name, attrs_of(e));
        break;
      case EntityRole::light:
      case EntityRole::object: {
        Json o = Json::object();
        // A plain light needs no type: "lights" entries are lights unless they say otherwise.
        if (e.kind != EntityKind::light) o["type"] = spec.keyword;
        if (!e.name.empty()) o["name"] = e.name;
        o.update(attrs_of(e));
        root[spec.role == EntityRole::light ? "lights" : "objects"].push_back(std::move(o));
        break;
      }
    }
  }
  if (with_render && !desc.render.empty()) {
    Json r = Json::object();
    for (const OptionValue& v : desc.render) r[v.name] = option_value(v.name, v.value);
    root["render"] = r;
  }
  return root.dump(2) + "\n";
}

}  // namespace rayfarm
