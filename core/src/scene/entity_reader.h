// One entity's attributes, checked against its row of the schema: what each kind's build
// function reads (scene/entities/*.cpp). Range errors are reported where the value was
// written; an absent optional attribute reads as its default.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>

#include <glm/vec3.hpp>

#include "rayfarm/scene.h"
#include "rayfarm/schema.h"

namespace rayfarm {

class SceneBuilder;

class EntityReader {
 public:
  EntityReader(const EntityDesc& e, SceneBuilder& builder, Diagnostics& diags);

  const EntityDesc& entity() const { return e_; }
  bool has(std::string_view key) const { return find(key) != nullptr; }
  const AttrDesc* find(std::string_view key) const;

  // Checked values; nullopt when absent and required, or when they were reported as wrong.
  std::optional<glm::dvec3> vec3(std::string_view key);
  std::optional<std::array<double, 2>> pair(std::string_view key);
  std::optional<double> number(std::string_view key);
  std::optional<int> integer(std::string_view key);
  std::optional<std::string> word(std::string_view key);
  // A material reference as an index into the scene's materials (reported when undefined).
  std::optional<int> material(std::string_view key);
  // A texture reference: the texture entity of that name, else the word read as a file path
  // (a texture of its own, shared by every use of the same path).
  std::optional<int> texture(std::string_view key);

  // "sphere 'ball'" for messages.
  std::string describe() const;
  static std::string describe(const EntityDesc& e);
  void error(std::string code, std::string message, const Where& where);
  void error_at_entity(std::string code, std::string message) { error(code, message, e_.where); }

  // The common part of every object: name, position, kind, material.
  Object object(int material, Shape shape) const {
    return {e_.name, e_.where, e_.kind, material, std::move(shape)};
  }

 private:
  // The values of an attribute after the range check of its kind; empty when absent and
  // required, or bad.
  std::optional<SmallVec<double, 3>> numbers(std::string_view key);

  const EntityDesc& e_;
  const EntitySpec& spec_;
  SceneBuilder& builder_;
  Diagnostics& diags_;
};

}  // namespace rayfarm
