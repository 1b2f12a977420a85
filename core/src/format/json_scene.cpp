// JSON scene parser: the document read by parse_json_tree (format/json_tree.h), then a walk
// that reports errors by JSON path.
#include "rayfarm/json_scene.h"

#include <nlohmann/json.hpp>

#include "format/json_tree.h"
#include "rayfarm/schema.h"

namespace rayfarm {
namespace {

using Json = nlohmann::ordered_json;

std::string child(const std::string& path, std::string_view key) {
  return path + "/" + json_pointer_token(key);
}
std::string child(const std::string& path, size_t index) {
  return path + "/" + std::to_string(index);
}

Where at(std::string path) { return {0, 0, std::move(path)}; }

// A key or string from the input for a message, shortened.
std::string printable(std::string_view s) {
  constexpr size_t kMax = 60;
  return s.size() > kMax ? std::string(s.substr(0, kMax)) + "..." : std::string(s);
}

// A JSON number written with a fraction or an exponent, as text in that form: 4.0 stays
// "4.0", so an integer option refuses it as the command line refuses --spp 4.0 (and a seed
// past 2^53 cannot pass through a double unnoticed).
std::string float_text(double v) {
  std::string s = format_number(v);
  if (s.find_first_of(".eEin") == std::string::npos) s += ".0";
  return s;
}

// Whether a render option's value is a list (written "R,G,B"): only such an option takes
// a JSON array.
bool takes_list(std::string_view key) {
  const OptionSpec* spec = find_option(key);
  return spec && spec->value_help.find(',') != std::string_view::npos;
}

std::string type_name(const Json& j) {
  if (j.is_number()) return "a number";
  return std::string(j.is_array() || j.is_object() ? "an " : "a ") + j.type_name();
}


class JsonSceneReader {
 public:
  explicit JsonSceneReader(Diagnostics& diags) : diags_(diags) {}

  // Each light and object's part of the tree is freed once read: the description then grows
  // into the tree's memory instead of beside it.
  SceneDesc read(Json& root) {
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
        if (!expect(value.is_object(), value, "an object of named cameras", path))
          stand_in(key, value, path, scene);
        else
          for (auto& [name, cam] : value.items()) {
            // (Only the one camera under "camera" goes unnamed.)
            if (name.empty())
              diags_.error("bad-name",
                           "a camera under \"cameras\" needs a name (its key); one unnamed "
                           "camera goes under \"camera\"",
                           at(child(path, name)));
            read_entity(EntityKind::camera, name, cam, child(path, name), scene);
          }
      } else if (key == "materials") {
        if (!expect(value.is_object(), value, "an object of named materials", path))
          stand_in(key, value, path, scene);
        else
          for (auto& [name, mat] : value.items())
            read_entity(EntityKind::material, name, mat, child(path, name), scene);
      } else if (key == "textures") {
        if (!expect(value.is_object(), value, "an object of named textures", path))
          stand_in(key, value, path, scene);
        else
          for (auto& [name, tex] : value.items())
            read_entity(EntityKind::texture, name, tex, child(path, name), scene);
      } else if (key == "lights") {
        if (expect(value.is_array(), value, "an array of lights", path))
          for (size_t i = 0; i < value.size(); ++i) {
            read_typed(EntityRole::light, value[i], child(path, i), scene);
            value[i] = nullptr;
          }
      } else if (key == "objects") {
        if (expect(value.is_array(), value, "an array of objects", path))
          for (size_t i = 0; i < value.size(); ++i) {
            read_typed(EntityRole::object, value[i], child(path, i), scene);
            value[i] = nullptr;
          }
      } else if (key == "render") {
        read_render(value, path, scene);
      } else {
        static constexpr std::string_view kKeys[] = {"camera",  "cameras", "materials", "textures",
                                                     "lights",  "objects", "render"};
        stand_in(unknown_key(key, kKeys, path), value, path, scene);
      }
    }
    return scene;
  }

 private:
  bool expect(bool ok, const Json& value, std::string_view what, const std::string& path) {
    if (!ok)
      diags_.error("json-type", "expected " + std::string(what) + ", got " + type_name(value),
                   at(path));
    return ok;
  }

  // A misspelt "camera", "cameras", "materials" or "textures" (the key it probably meant is
  // `meant`), or one of the wrong type, is one error: stand-ins of that kind, with the names
  // under it (an object's keys, or an array's "name"s, as lights and objects are written),
  // keep "no camera" and "undefined material" from following it, as a misspelt keyword's do
  // in a model file.
  void stand_in(const std::string& meant, const Json& value, const std::string& path,
                SceneDesc& scene) {
    if (meant == "camera") return add_stand_in(EntityKind::camera, "", path, scene);
    const EntityKind kind = meant == "cameras"     ? EntityKind::camera
                            : meant == "materials" ? EntityKind::material
                            : meant == "textures"  ? EntityKind::texture
                                                   : EntityKind::sphere;
    if (kind == EntityKind::sphere) return;
    const size_t before = scene.entities.size();
    if (value.is_object()) {
      for (auto& [name, entry] : value.items()) add_stand_in(kind, name, child(path, name), scene);
    } else if (value.is_array()) {
      for (size_t i = 0; i < value.size(); ++i) {
        if (!value[i].is_object()) continue;
        const auto name = value[i].find("name");
        if (name != value[i].end() && name->is_string())
          add_stand_in(kind, name->get<std::string>(), child(path, i), scene);
      }
    }
    // A camera even where none is named: "no camera" would follow otherwise.
    if (kind == EntityKind::camera && scene.entities.size() == before)
      add_stand_in(kind, "", path, scene);
  }

  void add_stand_in(EntityKind kind, const std::string& name, const std::string& path,
                    SceneDesc& scene) {
    EntityDesc e;
    e.kind = kind;
    e.name = is_valid_name(name) ? name : std::string();
    e.where = e.name_where = at(path);
    mark_all_invalid(e);
    scene.entities.push_back(std::move(e));
  }

  // Reports an unknown key; returns the key it probably meant, if any.
  std::string unknown_key(const std::string& key, std::span<const std::string_view> known,
                          const std::string& path) {
    std::string list;
    for (auto k : known) list += (list.empty() ? "" : ", ") + std::string(k);
    std::string hint = nearest_word(key, known);
    diags_.error("unknown-key",
                 "unknown key \"" + printable(key) + "\" (expected one of: " + list + ")" +
                     (hint.empty() ? "" : "; did you mean \"" + hint + "\"?"),
                 at(path));
    return hint;
  }

  // A light or an object: its "type" names the entity kind (a light's may be left out).
  void read_typed(EntityRole role, const Json& value, const std::string& path, SceneDesc& scene) {
    if (!expect(value.is_object(), value, "an object", path)) return;
    const auto kinds = keywords_of(role);
    std::string expected;
    for (size_t i = 0; i < kinds.size(); ++i)
      expected += std::string(i == 0 ? "" : i + 1 == kinds.size() ? " or " : ", ") + "\"" +
                  std::string(kinds[i]) + "\"";
    auto type = value.find("type");
    if (type == value.end()) {
      if (role == EntityRole::light) {
        read_entity(EntityKind::light, std::nullopt, value, path, scene);
        return;
      }
      diags_.error("missing-attribute", "object needs \"type\": " + expected, at(path));
      return;
    }
    // A type of another JSON type ("type": 5) is that, not an unknown kind named "5".
    if (!expect(type->is_string(), *type, "a string: " + expected, child(path, "type"))) return;
    const EntitySpec* spec = find_entity(type->get<std::string>());
    if (!spec || spec->role != role) {
      std::string got = type->get<std::string>();
      std::string hint = nearest_word(got, kinds);
      std::string why(unsupported_entity(got));
      diags_.error(why.empty() ? "unknown-entity" : "unsupported-entity",
                   why.empty() ? "unknown " + std::string(role == EntityRole::light ? "light" : "object") +
                                     " type \"" + printable(got) + "\" (expected " + expected + ")" +
                                     (hint.empty() ? "" : "; did you mean \"" + hint + "\"?")
                               : why,
                   at(child(path, "type")));
      return;
    }
    read_entity(spec->kind, std::nullopt, value, path, scene);
  }

  // `name` is set for entities named by their key (cameras, materials); nullopt when the
  // object may carry its own "name".
  void read_entity(EntityKind kind, std::optional<std::string> name, const Json& value,
                   const std::string& path, SceneDesc& scene) {
    const EntitySpec& spec = entity_spec(kind);
    if (!expect(value.is_object(), value, "an object", path)) {
      // A camera, material or texture of the wrong type still counts as one (the one error).
      if (kind == EntityKind::camera || kind == EntityKind::material ||
          kind == EntityKind::texture)
        add_stand_in(kind, name.value_or(""), path, scene);
      return;
    }
    EntityDesc e;
    e.kind = kind;
    e.where = at(path);
    if (name) {
      e.name = *name;
      e.name_where = at(path);
      if (!(kind == EntityKind::camera && name->empty()) && !is_valid_name(*name))
        diags_.error("bad-name",
                     "invalid " + std::string(spec.keyword) + " name \"" + printable(*name) +
                         "\": names are letters, digits, '_', '.', '-' and start with a letter "
                         "or '_'",
                     at(path));
    }
    std::vector<std::string_view> keys;
    for (const AttrSpec& a : spec.attrs) keys.push_back(a.key);
    bool own_name = !name.has_value();
    const bool typed = spec.role == EntityRole::light || spec.role == EntityRole::object;
    if (own_name) keys.push_back("name");
    if (typed) keys.push_back("type");
    // As many attributes as members, less the name and type: no room grown and left over
    // (a scene of many objects holds one of these per object).
    size_t members = value.size();
    if (own_name && value.contains("name")) --members;
    if (typed && value.contains("type")) --members;
    e.attrs.reserve(members);

    for (auto& [key, v] : value.items()) {
      std::string vpath = child(path, key);
      if (typed && key == "type") continue;
      if (own_name && key == "name") {
        if (expect(v.is_string(), v, "a name string", vpath)) {
          e.name = v.get<std::string>();
          e.name_where = at(vpath);
          if (!is_valid_name(e.name))
            diags_.error("bad-name", "invalid name \"" + printable(e.name) + "\"", at(vpath));
        }
        continue;
      }
      const AttrSpec* attr = find_attr(spec, key);
      if (!attr) {
        // The attribute it was meant to be is then not also "missing".
        std::string hint = unknown_key(key, keys, vpath);
        if (find_attr(spec, hint)) e.invalid_keys.push_back(hint);
        continue;
      }
      AttrDesc a;
      a.key = key;
      a.where = at(vpath);
      if (read_value(*attr, v, vpath, a))
        e.attrs.push_back(std::move(a));
      else
        e.invalid_keys.push_back(key);
    }
    scene.entities.push_back(std::move(e));
  }

  bool read_value(const AttrSpec& attr, const Json& v, const std::string& path, AttrDesc& a) {
    if (is_word_kind(attr.kind)) {
      const bool material = attr.kind == ValueKind::material_ref;
      if (!expect(v.is_string(), v, material ? "a material name" : describe(attr), path))
        return false;
      a.word = v.get<std::string>();
      if (material ? !is_valid_name(a.word) : !is_valid_path(a.word)) {
        diags_.error("bad-name",
                     std::string(material ? "invalid material name" : "invalid file name") +
                         " \"" + printable(a.word) + "\"",
                     at(path));
        return false;
      }
      a.value_where.push_json(false);
      return true;
    }
    auto [lo, hi] = value_count(attr.kind);
    if (v.is_number() && lo == 1) {
      a.numbers.push_back(v.get<double>());
      a.value_where.push_json(false);
      return true;
    }
    if (!v.is_array()) {
      expect(false, v, describe(attr), path);
      return false;
    }
    int n = static_cast<int>(std::min<size_t>(v.size(), 1000));
    if (n < lo || n > hi || (attr.kind == ValueKind::colour && n == 2)) {
      diags_.error("value-count",
                   "\"" + a.key + "\" takes " + describe(attr) + ", got " +
                       std::to_string(v.size()) + (v.size() == 1 ? " value" : " values"),
                   at(path));
      return false;
    }
    bool ok = true;
    for (size_t i = 0; i < v.size(); ++i) {
      if (!v[i].is_number()) {
        expect(false, v[i], "a number", child(path, i));
        ok = false;
        continue;
      }
      a.numbers.push_back(v[i].get<double>());
      a.value_where.push_json(true);
    }
    return ok;
  }

  void read_render(const Json& value, const std::string& path, SceneDesc& scene) {
    if (!expect(value.is_object(), value, "an object of render options", path)) return;
    for (auto& [key, v] : value.items()) {
      std::string vpath = child(path, key);
      std::string text;
      if (v.is_string())
        text = v.get<std::string>();
      else if (v.is_boolean())
        text = v.get<bool>() ? "true" : "false";
      else if (v.is_number_float())
        text = float_text(v.get<double>());
      else if (v.is_number())
        text = json_number_text(v);
      else if (v.is_array() && v.size() <= 3 && takes_list(key)) {
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
        diags_.error("bad-option",
                     "render option \"" + printable(key) + "\" has a value of the wrong type (" +
                         type_name(v) + ")",
                     at(vpath));
        continue;
      }
      scene.render.push_back({key, text, at(vpath)});
    }
  }

  Diagnostics& diags_;
};

}  // namespace

SceneDesc parse_json_scene(std::string_view text, Diagnostics& diags) {
  std::optional<Json> root = parse_json_tree(text, diags);
  if (!root) return {};
  return JsonSceneReader(diags).read(*root);
}

}  // namespace rayfarm
