// From a parsed SceneDesc to a checked Scene: required attributes, value ranges, names,
// material references and the camera rule (SPEC §1), reported for model and JSON alike.
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <string_view>
#include <vector>

#include "util/name_set.h"
#include "rayfarm/scene.h"
#include "rayfarm/schema.h"

namespace rayfarm {
namespace {

std::string describe_entity(const EntityDesc& e) {
  std::string s(entity_spec(e.kind).keyword);
  if (!e.name.empty()) s += " '" + e.name + "'";
  return s;
}

std::string position_text(const Where& w) {
  if (w.line > 0) return "line " + std::to_string(w.line);
  return w.path;
}

// The attributes of one entity by their place in its spec; like EntityDesc::find, the first
// one written wins. Looked up once per entity instead of once per use.
class AttrTable {
 public:
  explicit AttrTable(const EntityDesc& e) : e_(e), spec_(entity_spec(e.kind)) {
    if (spec_.attrs.size() > kSlots) return;  // never in the schema; fall back to find()
    indexed_ = true;
    for (const AttrDesc& a : e.attrs)
      for (size_t k = 0; k < spec_.attrs.size(); ++k)
        if (spec_.attrs[k].key == a.key) {
          if (!slot_[k]) slot_[k] = &a;
          break;
        }
  }

  const AttrDesc* find(std::string_view key) const {
    if (!indexed_) return e_.find(key);
    for (size_t k = 0; k < spec_.attrs.size(); ++k)
      if (spec_.attrs[k].key == key) return slot_[k];
    return nullptr;
  }
  const AttrDesc* at(size_t k) const { return indexed_ ? slot_[k] : e_.find(spec_.attrs[k].key); }

 private:
  static constexpr size_t kSlots = 8;
  const EntityDesc& e_;
  const EntitySpec& spec_;
  bool indexed_ = false;
  const AttrDesc* slot_[kSlots] = {};
};

// Checked values of one attribute (at most 3 numbers).
using Values = SmallVec<double, 3>;

class SceneBuilder {
 public:
  explicit SceneBuilder(Diagnostics& diags) : diags_(diags) {}

  std::optional<Scene> build(const SceneDesc& desc) {
    Scene scene;
    size_t count[5] = {};
    for (const EntityDesc& e : desc.entities) ++count[static_cast<int>(e.kind)];
    scene.cameras.reserve(count[static_cast<int>(EntityKind::camera)]);
    scene.materials.reserve(count[static_cast<int>(EntityKind::material)]);
    scene.lights.reserve(count[static_cast<int>(EntityKind::light)]);
    scene.spheres.reserve(count[static_cast<int>(EntityKind::sphere)]);
    scene.planes.reserve(count[static_cast<int>(EntityKind::plane)]);
    for (int k = 0; k < 5; ++k) name_sets_[k].reserve(count[k]);
    // Materials first: a sphere may use a material defined after it.
    for (const EntityDesc& e : desc.entities)
      if (e.kind == EntityKind::material) add_material(e, scene);
    for (const EntityDesc& e : desc.entities) {
      AttrTable attrs(e);
      check_required(e, attrs);
      switch (e.kind) {
        case EntityKind::camera:
          add_camera(e, attrs, scene);
          break;
        case EntityKind::material:
          break;
        case EntityKind::light:
          add_light(e, attrs, scene);
          break;
        case EntityKind::sphere:
          add_sphere(e, attrs, scene);
          break;
        case EntityKind::plane:
          add_plane(e, attrs, scene);
          break;
      }
    }
    if (scene.cameras.empty() && !had_camera_)
      diags_.error("no-camera", "no camera: a scene needs at least one camera", {});
    RenderOptions scratch;
    apply_options(scratch, desc.render, diags_);
    check_camera_option(desc.render);
    scene.render = desc.render;
    if (diags_.has_errors()) return std::nullopt;
    return scene;
  }

 private:
  // The scene's own "camera" option must name one of its cameras.
  void check_camera_option(const OptionSet& render) {
    const auto& cameras = names_[static_cast<int>(EntityKind::camera)];
    for (const OptionValue& v : render) {
      if (v.name != "camera" || v.value.empty() || cameras.count(v.value)) continue;
      if (!had_camera_ || v.value.size() > 256) continue;  // reported elsewhere
      std::vector<std::string_view> names;
      std::string list;
      for (auto& [name, where] : cameras) {
        names.push_back(name);
        list += (list.empty() ? "" : ", ") + name;
      }
      std::string hint = nearest_word(v.value, names);
      diags_.error("unknown-camera",
                   "render option camera names no camera '" + v.value + "'" +
                       (hint.empty() ? "" : " (did you mean '" + hint + "'?)") +
                       (list.empty() ? "; no camera has a name" : "; cameras: " + list),
                   v.where);
    }
  }

  void check_required(const EntityDesc& e, const AttrTable& attrs) {
    const EntitySpec& spec = entity_spec(e.kind);
    for (size_t k = 0; k < spec.attrs.size(); ++k) {
      const AttrSpec& a = spec.attrs[k];
      if (!a.required || attrs.at(k)) continue;
      if (std::find(e.invalid_keys.begin(), e.invalid_keys.end(), a.key) != e.invalid_keys.end())
        continue;
      diags_.error("missing-attribute",
                   describe_entity(e) + " is missing '" + std::string(a.key) + "' (" +
                       std::string(describe(a.kind)) + ")",
                   e.where);
    }
  }

  // Registers a name; reports a duplicate of the same entity type. Camera and material
  // names are also kept sorted, for the lists in messages about them.
  void check_name(const EntityDesc& e) {
    if (e.name.empty()) return;
    const EntityDesc* const* seen = name_sets_[static_cast<int>(e.kind)].insert(e.name, &e);
    if (!seen) {
      if (e.kind == EntityKind::camera || e.kind == EntityKind::material)
        names_[static_cast<int>(e.kind)].emplace(e.name, e.name_where);
      return;
    }
    diags_.error("duplicate-name",
                 "duplicate " + std::string(entity_spec(e.kind).keyword) + " name '" + e.name +
                     "' (first defined at " + position_text((*seen)->name_where) + ")",
                 e.name_where);
  }

  // Values of an attribute after the range check for its kind; empty when absent or bad.
  Values values(const AttrTable& attrs, const EntityDesc& e, std::string_view key) {
    const AttrDesc* a = attrs.find(key);
    const AttrSpec* spec = find_attr(entity_spec(e.kind), key);
    if (!a) {
      if (!spec || spec->required) return {};
      auto [lo, hi] = value_count(spec->kind);
      (void)lo;
      Values out;
      for (int i = 0; i < hi; ++i) out.push_back(spec->fallback[i]);
      return out;
    }
    bool ok = true;
    auto fail = [&](size_t i, const std::string& what) {
      Where w = i < a->value_where.size() ? a->value_where[i] : a->where;
      diags_.error("out-of-range",
                   "'" + a->key + "' " + what + ", got " + format_number(a->numbers[i]), w);
      ok = false;
    };
    for (size_t i = 0; i < a->numbers.size(); ++i)
      if (auto problem = value_problem(spec->kind, a->numbers[i]); !problem.empty())
        fail(i, std::string(problem));
    if (ok && spec->kind == ValueKind::direction && a->numbers.size() == 3 &&
        is_zero_vector(a->numbers.data())) {
      diags_.error("out-of-range", "'" + a->key + "' must not be the zero vector", a->where);
      ok = false;
    }
    if (!ok) return {};
    Values out = a->numbers;
    if (spec->kind == ValueKind::colour && out.size() == 1) out.assign(3, out[0]);
    return out;
  }

  static glm::dvec3 vec3(const Values& v) { return {v[0], v[1], v[2]}; }

  void add_camera(const EntityDesc& e, const AttrTable& attrs, Scene& scene) {
    had_camera_ = true;
    check_name(e);
    auto pix = values(attrs, e, "pixeldim");
    auto win = values(attrs, e, "worlddim");
    auto eye = values(attrs, e, "viewpoint");
    if (pix.size() != 2 || win.size() != 2 || eye.size() != 3) return;
    scene.cameras.push_back({e.name, e.where, static_cast<int>(pix[0]), static_cast<int>(pix[1]),
                             win[0], win[1], vec3(eye)});
  }

  void add_material(const EntityDesc& e, Scene& scene) {
    check_name(e);
    AttrTable attrs(e);
    auto ka = values(attrs, e, "ambient"), kd = values(attrs, e, "diffuse"),
         ks = values(attrs, e, "specular");
    auto n = values(attrs, e, "shininess");
    if (ka.size() != 3 || kd.size() != 3 || ks.size() != 3 || n.size() != 1) return;
    if (material_index_.count(e.name)) return;  // duplicate, reported
    material_index_[e.name] = static_cast<int>(scene.materials.size());
    scene.materials.push_back({e.name, e.where, vec3(ka), vec3(kd), vec3(ks), n[0]});
  }

  void add_light(const EntityDesc& e, const AttrTable& attrs, Scene& scene) {
    check_name(e);
    auto loc = values(attrs, e, "location"), em = values(attrs, e, "emissivity");
    if (loc.size() != 3 || em.size() != 3) return;
    scene.lights.push_back({e.name, e.where, vec3(loc), vec3(em)});
  }

  std::optional<int> material_of(const EntityDesc& e, const AttrTable& attrs) {
    const AttrDesc* a = attrs.find("material");
    if (!a) return std::nullopt;
    auto it = material_index_.find(a->word);
    if (it != material_index_.end()) return it->second;
    if (material_names_defined(a->word)) return std::nullopt;  // defined but broken: reported
    std::vector<std::string_view> names;
    std::string list;
    for (auto& [name, where] : names_[static_cast<int>(EntityKind::material)]) {
      names.push_back(name);
      if (names.size() <= 12) list += (list.empty() ? "" : ", ") + name;
    }
    if (names.size() > 12) list += ", ...";
    std::string hint = nearest_word(a->word, names);
    std::string msg = "undefined material '" + a->word + "' in " + describe_entity(e);
    if (!hint.empty()) msg += " (did you mean '" + hint + "'?)";
    msg += list.empty() ? "; no materials are defined" : "; defined: " + list;
    diags_.error("undefined-material", msg, a->value_where.empty() ? a->where : a->value_where[0]);
    return std::nullopt;
  }

  bool material_names_defined(const std::string& name) {
    return names_[static_cast<int>(EntityKind::material)].count(name) > 0;
  }

  void add_sphere(const EntityDesc& e, const AttrTable& attrs, Scene& scene) {
    check_name(e);
    auto c = values(attrs, e, "center"), r = values(attrs, e, "radius");
    auto m = material_of(e, attrs);
    if (c.size() != 3 || r.size() != 1 || !m) return;
    scene.spheres.push_back({e.name, e.where, vec3(c), r[0], *m});
  }

  void add_plane(const EntityDesc& e, const AttrTable& attrs, Scene& scene) {
    check_name(e);
    auto n = values(attrs, e, "normal"), p = values(attrs, e, "point");
    auto m = material_of(e, attrs);
    if (n.size() != 3 || p.size() != 3 || !m) return;
    scene.planes.push_back({e.name, e.where, vec3(n), vec3(p), *m});
  }

  Diagnostics& diags_;
  NameSet<const EntityDesc*> name_sets_[5];  // the scene description outlives the builder
  std::map<std::string, Where> names_[5];  // cameras and materials only
  std::map<std::string, int> material_index_;
  bool had_camera_ = false;
};

}  // namespace

std::optional<int> Scene::find_camera(std::string_view name) const {
  if (cameras.empty()) return std::nullopt;
  if (name.empty()) return 0;
  for (size_t i = 0; i < cameras.size(); ++i)
    if (cameras[i].name == name) return static_cast<int>(i);
  return std::nullopt;
}

std::optional<Scene> build_scene(const SceneDesc& desc, Diagnostics& diags) {
  return SceneBuilder(diags).build(desc);
}

}  // namespace rayfarm
