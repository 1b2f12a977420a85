// From a parsed SceneDesc to a checked Scene: each kind builds itself from its checked
// attributes (scene/entities/); here are the rules across entities: required attributes,
// names, material and texture references, and the camera rule. Model and JSON alike.
#include <algorithm>
#include <cmath>
#include <map>
#include <string_view>
#include <vector>

#include "scene/registry.h"
#include "util/name_set.h"

namespace rayfarm {
namespace {

std::string position_text(const Where& w) {
  if (w.line > 0) return "line " + std::to_string(w.line);
  return w.path;
}

// "did you mean" and the list of defined names, for a reference to an undefined one.
std::string undefined_message(const std::string& what, const std::string& name,
                              const std::string& in, const std::map<std::string, Where>& defined) {
  // Each of many such references must not walk every name (nearest_word takes a bounded
  // number of candidates).
  std::vector<std::string_view> names;
  std::string list;
  int listed = 0;
  for (auto it = defined.begin(); it != defined.end() && listed < 12; ++it, ++listed)
    list += (list.empty() ? "" : ", ") + it->first;
  if (defined.size() > 12) list += ", ...";
  if (defined.size() <= kMaxHintCandidates)
    for (auto& [n, where] : defined) names.push_back(n);
  std::string hint = nearest_word(name, names);
  std::string msg = "undefined " + what + " '" + name + "' in " + in;
  if (!hint.empty()) msg += " (did you mean '" + hint + "'?)";
  msg += list.empty() ? "; no " + what + "s are defined" : "; defined: " + list;
  return msg;
}

}  // namespace

class SceneBuilder {
 public:
  explicit SceneBuilder(Diagnostics& diags) : diags_(diags) {}

  std::optional<Scene> build(const SceneDesc& desc) {
    Scene scene;
    size_t count[kEntityKinds] = {};
    for (const EntityDesc& e : desc.entities) ++count[static_cast<int>(e.kind)];
    for (int k = 0; k < kEntityKinds; ++k) name_sets_[k].reserve(count[k]);
    size_t objects = 0;
    for (int k = 0; k < kEntityKinds; ++k)
      if (entity_spec(static_cast<EntityKind>(k)).role == EntityRole::object) objects += count[k];
    scene.objects.reserve(objects);
    // Materials and textures first: an object may use one defined after it.
    for (const EntityDesc& e : desc.entities)
      if (e.kind == EntityKind::material) add_material(e, scene);
    for (const EntityDesc& e : desc.entities)
      if (e.kind == EntityKind::texture) add_texture(e, scene);
    for (const EntityDesc& e : desc.entities) {
      check_required(e);
      if (e.kind == EntityKind::material || e.kind == EntityKind::texture) continue;
      had_camera_ = had_camera_ || e.kind == EntityKind::camera;
      check_name(e);
      scene_ = &scene;
      EntityReader reader(e, *this, diags_);
      entity_hooks(e.kind).build(reader, scene);
    }
    if (scene.cameras.empty() && !had_camera_)
      diags_.error("no-camera", "no camera: a scene needs at least one camera", {});
    RenderOptions scratch;
    const size_t errors_before = diags_.error_count();
    apply_options(scratch, desc.render, diags_);
    if (diags_.error_count() == errors_before) check_profile(desc.render, scratch);
    check_camera_option(desc.render);
    scene.render = desc.render;
    if (diags_.has_errors()) return std::nullopt;
    return scene;
  }

  std::optional<int> material(const AttrDesc& a, const std::string& in) {
    auto it = material_index_.find(a.word);
    if (it != material_index_.end()) return it->second;
    if (names_[static_cast<int>(EntityKind::material)].count(a.word))
      return std::nullopt;  // defined but broken: reported
    diags_.error("undefined-material",
                 undefined_message("material", a.word, in,
                                   names_[static_cast<int>(EntityKind::material)]),
                 a.value_at(0));
    return std::nullopt;
  }

  // A texture entity by name; otherwise the word is a path, one texture per distinct path.
  std::optional<int> texture(const AttrDesc& a) {
    if (auto it = texture_index_.find(a.word); it != texture_index_.end()) return it->second;
    if (names_[static_cast<int>(EntityKind::texture)].count(a.word))
      return std::nullopt;  // defined but broken: reported
    const Where where = a.value_at(0);
    if (!is_valid_path(a.word)) {
      diags_.error("bad-path", "'" + a.key + "' is neither a texture's name nor a file path",
                   where);
      return std::nullopt;
    }
    if (auto it = path_index_.find(a.word); it != path_index_.end()) return it->second;
    const int index = static_cast<int>(scene_->textures.size());
    scene_->textures.push_back({"", where, a.word, where, nullptr});
    path_index_[a.word] = index;
    return index;
  }

 private:
  void add_material(const EntityDesc& e, Scene& scene) {
    check_name(e);
    EntityReader reader(e, *this, diags_);
    const size_t before = scene.materials.size();
    entity_hooks(e.kind).build(reader, scene);
    if (scene.materials.size() == before || material_index_.count(e.name)) return;
    material_index_[e.name] = static_cast<int>(before);
  }

  void add_texture(const EntityDesc& e, Scene& scene) {
    check_name(e);
    EntityReader reader(e, *this, diags_);
    auto path = reader.word("filename");
    if (!path || texture_index_.count(e.name)) return;
    const AttrDesc* a = e.find("filename");
    texture_index_[e.name] = static_cast<int>(scene.textures.size());
    scene.textures.push_back({e.name, e.where, *path, a->value_at(0), nullptr});
  }

  // The scene's own options must suit its own profile (a render then never refuses them),
  // reported at the option at fault, else at the profile's.
  void check_profile(const OptionSet& render, const RenderOptions& options) {
    std::string option;
    const std::string conflict = profile_conflict(options, &option);
    if (conflict.empty()) return;
    Where where;
    for (const OptionValue& v : render)
      if (v.name == option || (where.path.empty() && where.line == 0 && v.name == "profile"))
        where = v.where;
    diags_.error("bad-option", conflict, where);
  }

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

  void check_required(const EntityDesc& e) {
    const EntitySpec& spec = entity_spec(e.kind);
    for (const AttrSpec& a : spec.attrs) {
      if (!a.required || e.find(a.key)) continue;
      if (std::find(e.invalid_keys.begin(), e.invalid_keys.end(), a.key) != e.invalid_keys.end())
        continue;
      diags_.error("missing-attribute",
                   EntityReader::describe(e) + " is missing '" + std::string(a.key) + "' (" +
                       describe(a) + ")",
                   e.where);
    }
  }

  // Registers a name; reports a duplicate of the same entity type. Names that others refer
  // to (cameras, materials, textures) are also kept sorted, for the lists in messages.
  void check_name(const EntityDesc& e) {
    if (e.name.empty()) return;
    const EntityDesc* const* seen = name_sets_[static_cast<int>(e.kind)].insert(e.name, &e);
    if (!seen) {
      if (e.kind == EntityKind::camera || e.kind == EntityKind::material ||
          e.kind == EntityKind::texture)
        names_[static_cast<int>(e.kind)].emplace(e.name, e.name_where);
      return;
    }
    diags_.error("duplicate-name",
                 "duplicate " + std::string(entity_spec(e.kind).keyword) + " name '" + e.name +
                     "' (first defined at " + position_text((*seen)->name_where) + ")",
                 e.name_where);
  }

  Diagnostics& diags_;
  Scene* scene_ = nullptr;
  NameSet<const EntityDesc*> name_sets_[kEntityKinds];  // the description outlives the builder
  std::map<std::string, Where> names_[kEntityKinds];   // cameras, materials, textures only
  std::map<std::string, int> material_index_;
  std::map<std::string, int> texture_index_;
  std::map<std::string, int> path_index_;  // textures named by path alone
  bool had_camera_ = false;
};

// --- EntityReader ---------------------------------------------------------------------

EntityReader::EntityReader(const EntityDesc& e, SceneBuilder& builder, Diagnostics& diags)
    : e_(e), spec_(entity_spec(e.kind)), builder_(builder), diags_(diags) {}

const AttrDesc* EntityReader::find(std::string_view key) const { return e_.find(key); }

std::string EntityReader::describe(const EntityDesc& e) {
  std::string s(entity_spec(e.kind).keyword);
  if (!e.name.empty()) s += " '" + e.name + "'";
  return s;
}

std::string EntityReader::describe() const { return describe(e_); }

void EntityReader::error(std::string code, std::string message, const Where& where) {
  diags_.error(std::move(code), std::move(message), where);
}

std::optional<SmallVec<double, 3>> EntityReader::numbers(std::string_view key) {
  const AttrDesc* a = find(key);
  const AttrSpec* spec = find_attr(spec_, key);
  if (!spec) return std::nullopt;
  if (!a) {
    if (spec->required) return std::nullopt;
    SmallVec<double, 3> out;
    for (int i = 0; i < value_count(spec->kind)[1]; ++i) out.push_back(spec->fallback[i]);
    return out;
  }
  bool ok = true;
  for (size_t i = 0; i < a->numbers.size(); ++i)
    if (auto problem = value_problem(*spec, a->numbers[i]); !problem.empty()) {
      const Where w = a->value_at(i);
      diags_.error("out-of-range",
                   "'" + a->key + "' " + problem + ", got " + format_number(a->numbers[i]), w);
      ok = false;
    }
  if (ok && spec->kind == ValueKind::direction && a->numbers.size() == 3 &&
      is_zero_vector(a->numbers.data())) {
    diags_.error("out-of-range", "'" + a->key + "' must not be the zero vector", a->where);
    ok = false;
  }
  if (!ok) return std::nullopt;
  SmallVec<double, 3> out = a->numbers;
  if (spec->kind == ValueKind::colour && out.size() == 1) out.assign(3, out[0]);
  return out;
}

std::optional<glm::dvec3> EntityReader::vec3(std::string_view key) {
  auto v = numbers(key);
  if (!v || v->size() != 3) return std::nullopt;
  return glm::dvec3{(*v)[0], (*v)[1], (*v)[2]};
}

std::optional<std::array<double, 2>> EntityReader::pair(std::string_view key) {
  auto v = numbers(key);
  if (!v || v->size() != 2) return std::nullopt;
  return std::array<double, 2>{(*v)[0], (*v)[1]};
}

std::optional<double> EntityReader::number(std::string_view key) {
  auto v = numbers(key);
  if (!v || v->size() != 1) return std::nullopt;
  return (*v)[0];
}

std::optional<int> EntityReader::integer(std::string_view key) {
  auto v = number(key);
  if (!v) return std::nullopt;
  return static_cast<int>(*v);
}

std::optional<std::string> EntityReader::word(std::string_view key) {
  const AttrDesc* a = find(key);
  if (!a) return std::nullopt;
  return a->word;
}

std::optional<int> EntityReader::material(std::string_view key) {
  const AttrDesc* a = find(key);
  if (!a) return std::nullopt;
  return builder_.material(*a, describe());
}

std::optional<int> EntityReader::texture(std::string_view key) {
  const AttrDesc* a = find(key);
  if (!a) return std::nullopt;
  return builder_.texture(*a);
}

namespace {
double max_abs(const glm::dvec3& v) {
  return std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
}
double max_size(const Window& w) { return std::max(std::abs(w.width), std::abs(w.height)); }
}  // namespace

double largest_magnitude(const Shape& shape) {
  struct {
    double operator()(const Sphere& s) const { return max_abs(s.center) + std::abs(s.radius); }
    double operator()(const Plane& p) const { return max_abs(p.point); }
    double operator()(const FinitePlane& f) const {
      return max_abs(f.plane.point) + max_size(f.window);
    }
    double operator()(const TiledPlane& t) const {
      return std::max(max_abs(t.plane.point), max_size(t.tile));
    }
    double operator()(const TexPlane& t) const {
      return max_abs(t.plane.point) + max_size(t.window);
    }
    double operator()(const Triangle& t) const {
      double m = t.plane ? max_abs(t.plane->point) : 0;
      for (const glm::dvec3& v : t.vertex) m = std::max(m, max_abs(v));
      return m;
    }
    double operator()(const Revsurf& r) const { return max_abs(r.base) + std::abs(r.height); }
  } of;
  return visit_shape(of, shape);
}

double largest_magnitude(const Light& l) {
  double m = std::max(max_abs(l.location), max_abs(l.aim));
  if (l.kind == LightKind::projector) m = std::max(m, max_abs(l.point) + max_size(l.window));
  return m;
}

std::optional<int> Scene::find_camera(std::string_view name) const {
  if (cameras.empty()) return std::nullopt;
  if (name.empty()) return 0;
  for (size_t i = 0; i < cameras.size(); ++i)
    if (cameras[i].name == name) return static_cast<int>(i);
  return std::nullopt;
}

std::string Scene::camera_names() const {
  std::string names;
  int unnamed = 0;
  for (const Camera& c : cameras) {
    if (c.name.empty())
      ++unnamed;
    else
      names += (names.empty() ? "" : ", ") + c.name;
  }
  if (unnamed > 0) names += (names.empty() ? "" : "; ") + std::to_string(unnamed) + " unnamed";
  return names;
}

std::optional<Scene> build_scene(const SceneDesc& desc, Diagnostics& diags) {
  return SceneBuilder(diags).build(desc);
}

}  // namespace rayfarm
