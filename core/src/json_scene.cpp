// JSON scene parser: nlohmann_json with a callback that bounds nesting and catches duplicate
// keys (the library silently keeps the last), then a walk that reports errors by JSON path.
#include "rayfarm/json_scene.h"

#include <nlohmann/json.hpp>
#include <set>

#include "rayfarm/schema.h"

namespace rayfarm {
namespace {

using Json = nlohmann::ordered_json;

std::string pointer_token(std::string_view key) {
  std::string out;
  for (char c : key) {
    if (c == '~') out += "~0";
    else if (c == '/') out += "~1";
    else out += c;
  }
  return out;
}

std::string child(const std::string& path, std::string_view key) {
  return path + "/" + pointer_token(key);
}
std::string child(const std::string& path, size_t index) {
  return path + "/" + std::to_string(index);
}

Where at(std::string path) { return {0, 0, std::move(path)}; }

std::string type_name(const Json& j) {
  if (j.is_number()) return "a number";
  return std::string(j.is_array() ? "an " : "a ") + j.type_name();
}

// Tracks the JSON pointer of the value being parsed, for errors the callback finds.
class ParseWatch {
 public:
  bool on_event(int depth, Json::parse_event_t event, Json& parsed) {
    using E = Json::parse_event_t;
    if (depth > kMaxJsonDepth) {
      too_deep_ = true;
      return false;
    }
    switch (event) {
      case E::object_start:
      case E::array_start:
        element_started();
        frames_.push_back({event == E::array_start, -1, {}, {}});
        break;
      case E::key: {
        Frame& f = frames_.back();
        f.key = parsed.get<std::string>();
        if (!f.keys.insert(f.key).second && duplicates_.size() < 20)
          duplicates_.push_back(path() );
        break;
      }
      case E::value:
        element_started();
        break;
      case E::object_end:
      case E::array_end:
        if (!frames_.empty()) frames_.pop_back();
        break;
    }
    return true;
  }

  bool too_deep() const { return too_deep_; }
  const std::vector<std::string>& duplicates() const { return duplicates_; }

 private:
  struct Frame {
    bool array;
    long index;
    std::string key;
    std::set<std::string> keys;
  };

  void element_started() {
    if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
  }

  std::string path() const {
    std::string p;
    for (const Frame& f : frames_)
      p += f.array ? "/" + std::to_string(f.index) : "/" + pointer_token(f.key);
    return p;
  }

  std::vector<Frame> frames_;
  std::vector<std::string> duplicates_;
  bool too_deep_ = false;
};

class JsonSceneReader {
 public:
  explicit JsonSceneReader(Diagnostics& diags) : diags_(diags) {}

  SceneDesc read(const Json& root) {
    SceneDesc scene;
    if (!root.is_object()) {
      diags_.error("json-type", "a scene must be a JSON object, not " + type_name(root), at(""));
      return scene;
    }
    if (root.contains("camera") && root.contains("cameras"))
      diags_.error("json-key", "give either \"camera\" or \"cameras\", not both", at("/cameras"));
    for (auto& [key, value] : root.items()) {
      std::string path = child("", key);
      if (key == "camera") {
        read_entity(EntityKind::camera, "", value, path, scene);
      } else if (key == "cameras") {
        if (expect(value.is_object(), value, "an object of named cameras", path))
          for (auto& [name, cam] : value.items())
            read_entity(EntityKind::camera, name, cam, child(path, name), scene);
      } else if (key == "materials") {
        if (expect(value.is_object(), value, "an object of named materials", path))
          for (auto& [name, mat] : value.items())
            read_entity(EntityKind::material, name, mat, child(path, name), scene);
      } else if (key == "lights") {
        if (expect(value.is_array(), value, "an array of lights", path))
          for (size_t i = 0; i < value.size(); ++i)
            read_entity(EntityKind::light, std::nullopt, value[i], child(path, i), scene);
      } else if (key == "objects") {
        if (expect(value.is_array(), value, "an array of objects", path))
          for (size_t i = 0; i < value.size(); ++i) read_object(value[i], child(path, i), scene);
      } else if (key == "render") {
        read_render(value, path, scene);
      } else {
        static constexpr std::string_view kKeys[] = {"camera", "cameras", "materials",
                                                     "lights", "objects", "render"};
        unknown_key(key, kKeys, path);
      }
    }
    return scene;
  }

 private:
  bool expect(bool ok, const Json& value, std::string_view what, const std::string& path) {
    if (!ok) diags_.error("json-type", "expected " + std::string(what) + ", got " +
                                           type_name(value), at(path));
    return ok;
  }

  void unknown_key(const std::string& key, std::span<const std::string_view> known,
                   const std::string& path) {
    std::string list;
    for (auto k : known) list += (list.empty() ? "" : ", ") + std::string(k);
    std::string hint = nearest_word(key, known);
    diags_.error("unknown-key",
                 "unknown key \"" + key.substr(0, 60) + "\" (expected one of: " + list + ")" +
                     (hint.empty() ? "" : "; did you mean \"" + hint + "\"?"),
                 at(path));
  }

  void read_object(const Json& value, const std::string& path, SceneDesc& scene) {
    if (!expect(value.is_object(), value, "an object", path)) return;
    auto type = value.find("type");
    if (type == value.end()) {
      diags_.error("missing-attribute", "object needs \"type\": \"sphere\" or \"plane\"",
                   at(path));
      return;
    }
    if (!type->is_string() || (*type != "sphere" && *type != "plane")) {
      std::string got = type->is_string() ? type->get<std::string>() : type->dump();
      static constexpr std::string_view kTypes[] = {"sphere", "plane"};
      std::string hint = nearest_word(got, kTypes);
      diags_.error("unknown-entity",
                   "unknown object type \"" + got.substr(0, 60) +
                       "\" (expected \"sphere\" or \"plane\")" +
                       (hint.empty() ? "" : "; did you mean \"" + hint + "\"?"),
                   at(child(path, "type")));
      return;
    }
    EntityKind kind = *type == "sphere" ? EntityKind::sphere : EntityKind::plane;
    read_entity(kind, std::nullopt, value, path, scene);
  }

  // `name` is set for entities named by their key (cameras, materials); nullopt when the
  // object may carry its own "name".
  void read_entity(EntityKind kind, std::optional<std::string> name, const Json& value,
                   const std::string& path, SceneDesc& scene) {
    const EntitySpec& spec = entity_spec(kind);
    if (!expect(value.is_object(), value, "an object", path)) return;
    EntityDesc e;
    e.kind = kind;
    e.where = at(path);
    if (name) {
      e.name = *name;
      e.name_where = at(path);
      if (!(kind == EntityKind::camera && name->empty()) && !is_valid_name(*name))
        diags_.error("bad-name",
                     "invalid " + std::string(spec.keyword) + " name \"" + name->substr(0, 60) +
                         "\": names are letters, digits, '_', '.', '-' and start with a letter "
                         "or '_'",
                     at(path));
    }
    std::vector<std::string_view> keys;
    for (const AttrSpec& a : spec.attrs) keys.push_back(a.key);
    bool own_name = !name.has_value();
    bool typed = kind == EntityKind::sphere || kind == EntityKind::plane;
    if (own_name) keys.push_back("name");
    if (typed) keys.push_back("type");

    for (auto& [key, v] : value.items()) {
      std::string vpath = child(path, key);
      if (typed && key == "type") continue;
      if (own_name && key == "name") {
        if (expect(v.is_string(), v, "a name string", vpath)) {
          e.name = v.get<std::string>();
          e.name_where = at(vpath);
          if (!is_valid_name(e.name))
            diags_.error("bad-name", "invalid name \"" + e.name.substr(0, 60) + "\"", at(vpath));
        }
        continue;
      }
      const AttrSpec* attr = find_attr(spec, key);
      if (!attr) {
        unknown_key(key, keys, vpath);
        continue;
      }
      AttrDesc a;
      a.key = key;
      a.where = at(vpath);
      if (read_value(*attr, v, vpath, a)) e.attrs.push_back(std::move(a));
      else e.invalid_keys.push_back(key);
    }
    scene.entities.push_back(std::move(e));
  }

  bool read_value(const AttrSpec& attr, const Json& v, const std::string& path, AttrDesc& a) {
    if (attr.kind == ValueKind::material_ref) {
      if (!expect(v.is_string(), v, "a material name", path)) return false;
      a.word = v.get<std::string>();
      a.value_where.push_back(at(path));
      return true;
    }
    auto [lo, hi] = value_count(attr.kind);
    if (v.is_number() && lo == 1) {
      a.numbers.push_back(v.get<double>());
      a.value_where.push_back(at(path));
      return true;
    }
    if (!v.is_array()) {
      expect(false, v, describe(attr.kind), path);
      return false;
    }
    int n = static_cast<int>(v.size());
    if (n < lo || n > hi || (hi == 3 && lo == 1 && n == 2)) {
      diags_.error("value-count",
                   "\"" + a.key + "\" takes " + std::string(describe(attr.kind)) + ", got " +
                       std::to_string(n) + (n == 1 ? " value" : " values"),
                   at(path));
      return false;
    }
    bool ok = true;
    for (size_t i = 0; i < v.size(); ++i) {
      std::string ipath = child(path, i);
      if (!expect(v[i].is_number(), v[i], "a number", ipath)) {
        ok = false;
        continue;
      }
      a.numbers.push_back(v[i].get<double>());
      a.value_where.push_back(at(ipath));
    }
    return ok;
  }

  void read_render(const Json& value, const std::string& path, SceneDesc& scene) {
    if (!expect(value.is_object(), value, "an object of render options", path)) return;
    for (auto& [key, v] : value.items()) {
      std::string vpath = child(path, key);
      std::string text;
      if (v.is_string()) text = v.get<std::string>();
      else if (v.is_boolean()) text = v.get<bool>() ? "true" : "false";
      else if (v.is_number_unsigned()) text = std::to_string(v.get<std::uint64_t>());
      else if (v.is_number_integer()) text = std::to_string(v.get<std::int64_t>());
      else if (v.is_number()) text = format_number(v.get<double>());
      else if (v.is_array() && v.size() <= 3) {
        for (const Json& c : v) {
          if (!c.is_number()) {
            text = "?";
            break;
          }
          text += (text.empty() ? "" : ",") + format_number(c.get<double>());
        }
      } else {
        text = "?";
      }
      if (text == "?") {
        diags_.error("bad-option", "render option \"" + key.substr(0, 60) +
                                       "\" has a value of the wrong type (" + type_name(v) + ")",
                     at(vpath));
        continue;
      }
      scene.render.push_back({key, text, at(vpath)});
    }
  }

  Diagnostics& diags_;
};

// nlohmann's message after its "[json.exception...] parse error at line L, column C: " prefix.
std::string parse_error_text(const std::string& what) {
  size_t colon = what.find(": ");
  std::string text = colon == std::string::npos ? what : what.substr(colon + 2);
  return text;
}

}  // namespace

SceneDesc parse_json_scene(std::string_view text, Diagnostics& diags) {
  ParseWatch watch;
  Json root;
  try {
    root = Json::parse(text.begin(), text.end(),
                       [&watch](int depth, Json::parse_event_t event, Json& parsed) {
                         return watch.on_event(depth, event, parsed);
                       });
  } catch (const Json::parse_error& e) {
    // Position from the byte offset nlohmann reports (1-based, one past the error).
    size_t offset = e.byte > 0 ? std::min<size_t>(e.byte - 1, text.size()) : 0;
    int line = 1, column = 1;
    for (size_t i = 0; i < offset; ++i) {
      if (text[i] == '\n') {
        ++line;
        column = 1;
      } else {
        ++column;
      }
    }
    diags.error("json-syntax", "invalid JSON: " + parse_error_text(e.what()),
                {line, column, {}});
    return {};
  } catch (const Json::exception& e) {
    diags.error("json-syntax", std::string("invalid JSON: ") + e.what(), {});
    return {};
  }
  if (watch.too_deep()) {
    diags.error("json-depth",
                "JSON nested deeper than " + std::to_string(kMaxJsonDepth) + " levels", at(""));
    return {};
  }
  for (const std::string& path : watch.duplicates())
    diags.error("duplicate-key", "key given twice", at(path));
  return JsonSceneReader(diags).read(root);
}

}  // namespace rayfarm
