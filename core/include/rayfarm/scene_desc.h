// A parsed scene exactly as written, before any defaults or checks beyond syntax:
// a list of entities with their attributes and source positions. Both the model-file and
// the JSON parser produce it; validation, conversion and scene building consume it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "rayfarm/diagnostic.h"
#include "rayfarm/options.h"

namespace rayfarm {

enum class EntityKind { camera, material, light, sphere, plane };

struct AttrDesc {
  std::string key;
  std::vector<double> numbers;  // numeric values as written (a one-number colour stays one)
  std::string word;             // for name-valued attributes (sphere material)
  Where where;                  // the attribute keyword
  std::vector<Where> value_where;
};

struct EntityDesc {
  EntityKind kind = EntityKind::camera;
  std::string name;  // empty when the model file gave none
  Where where;       // the entity keyword
  Where name_where;
  std::vector<AttrDesc> attrs;
  // Attributes that were written but had errors: not "missing", and not reported again.
  std::vector<std::string> invalid_keys;

  const AttrDesc* find(std::string_view key) const;
};

struct SceneDesc {
  std::vector<EntityDesc> entities;
  // Render options carried by the scene itself (the JSON "render" object).
  OptionSet render;
};

}  // namespace rayfarm
