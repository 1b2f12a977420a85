// SceneDesc to the JSON scene format (SPEC §2).
#include <cmath>
#include <nlohmann/json.hpp>

#include "rayfarm/schema.h"
#include "rayfarm/writers.h"

namespace rayfarm {
namespace {

using Json = nlohmann::ordered_json;

Json number(double v) {
  // Integral values print as integers ("800", not "800.0").
  if (v == std::floor(v) && std::fabs(v) < 9e15) return static_cast<long long>(v);
  return v;
}

Json attr_value(const AttrSpec& spec, const AttrDesc& a) {
  if (spec.kind == ValueKind::material_ref) return a.word;
  if (a.numbers.size() == 1 && (spec.kind == ValueKind::positive || spec.kind == ValueKind::colour))
    return number(a.numbers[0]);
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

Json option_value(const std::string& name, const std::string& text) {
  if (text == "true") return true;
  if (text == "false") return false;
  if (name == "background") {
    Json arr = Json::array();
    size_t start = 0;
    while (start <= text.size()) {
      size_t comma = text.find(',', start);
      std::string part = text.substr(start, comma == std::string::npos ? comma : comma - start);
      try {
        arr.push_back(number(std::stod(part)));
      } catch (...) {
        return text;
      }
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
    return arr;
  }
  char* end = nullptr;
  double v = std::strtod(text.c_str(), &end);
  if (!text.empty() && end == text.c_str() + text.size() && std::isfinite(v)) return number(v);
  return text;
}

}  // namespace

std::string write_json(const SceneDesc& desc) {
  Json root = Json::object();
  int cameras = 0;
  bool all_named = true;
  for (const EntityDesc& e : desc.entities)
    if (e.kind == EntityKind::camera) {
      ++cameras;
      all_named = all_named && !e.name.empty();
    }
  bool single = cameras == 1 && !all_named;
  int unnamed = 0;
  for (const EntityDesc& e : desc.entities) {
    switch (e.kind) {
      case EntityKind::camera:
        if (single) root["camera"] = attrs_of(e);
        else root["cameras"][e.name.empty() ? "camera" + std::to_string(++unnamed) : e.name] =
            attrs_of(e);
        break;
      case EntityKind::material: root["materials"][e.name] = attrs_of(e); break;
      case EntityKind::light: {
        Json l = Json::object();
        if (!e.name.empty()) l["name"] = e.name;
        l.update(attrs_of(e));
        root["lights"].push_back(l);
        break;
      }
      case EntityKind::sphere:
      case EntityKind::plane: {
        Json o = Json::object();
        o["type"] = entity_spec(e.kind).keyword;
        if (!e.name.empty()) o["name"] = e.name;
        o.update(attrs_of(e));
        root["objects"].push_back(o);
        break;
      }
    }
  }
  if (!desc.render.empty()) {
    Json r = Json::object();
    for (const OptionValue& v : desc.render) r[v.name] = option_value(v.name, v.value);
    root["render"] = r;
  }
  return root.dump(2) + "\n";
}

}  // namespace rayfarm
