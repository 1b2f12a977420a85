// SceneDesc to the JSON scene format (docs/json-format.md).
#include <algorithm>
#include <charconv>
#include <string>
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

// The fewest digits that read back as `v` (finite): fixed from 1e-6 to 1e15 ("0.0008"),
// otherwise with an exponent ("1e-07", "1e+23"); always with a '.' or an exponent, so that it
// reads back as a double ("-0.0", not the integer "-0").
std::string json_double(double v) {
  char sci[64], fixed[400];
  const auto s = std::to_chars(sci, sci + sizeof sci, v, std::chars_format::scientific);
  const std::string_view text(sci, static_cast<size_t>(s.ptr - sci));
  const size_t e = text.find('e');
  const int exponent = std::stoi(std::string(text.substr(e + 1)));
  const auto digits = std::count_if(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(e),
                                    [](char c) { return c >= '0' && c <= '9'; });
  if (exponent < -6 || exponent >= 15) return std::string(text);
  const int decimals = std::max(1, static_cast<int>(digits) - 1 - exponent);
  const auto f = std::to_chars(fixed, fixed + sizeof fixed, v, std::chars_format::fixed, decimals);
  return std::string(fixed, f.ptr);
}

// As nlohmann's dump(2) lays JSON out, but a double in the shortest text that reads back as
// it (json_double, above): the library's Grisu2 is not always shortest
// (1e23 came out 9.999999999999999e+22).
void write_pretty(const Json& j, int indent, std::string& out) {
  const std::string pad(static_cast<size_t>(indent) + 2, ' ');
  if (j.is_object() && !j.empty()) {
    out += "{\n";
    bool first = true;
    for (auto& [key, value] : j.items()) {
      out += (first ? "" : ",\n") + pad + Json(key).dump() + ": ";
      write_pretty(value, indent + 2, out);
      first = false;
    }
    out += "\n" + std::string(static_cast<size_t>(indent), ' ') + "}";
  } else if (j.is_array() && !j.empty()) {
    out += "[\n";
    for (size_t i = 0; i < j.size(); ++i) {
      out += (i ? ",\n" : "") + pad;
      write_pretty(j[i], indent + 2, out);
    }
    out += "\n" + std::string(static_cast<size_t>(indent), ' ') + "]";
  } else if (j.is_number_float()) {
    out += json_double(j.get<double>());
  } else {
    out += j.dump();
  }
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
  std::string out;
  write_pretty(root, 0, out);
  return out + "\n";
}

}  // namespace rayfarm
