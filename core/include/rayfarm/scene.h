// A checked scene with every default applied: what the renderer, the linter and the
// POV-Ray exporter work from. Built only from a SceneDesc without errors.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "rayfarm/diagnostic.h"
#include "rayfarm/options.h"
#include "rayfarm/scene_desc.h"

namespace rayfarm {

struct Camera {
  std::string name;
  Where where;  // the entity in the source
  int width = 0;
  int height = 0;
  double world_width = 0;
  double world_height = 0;
  glm::dvec3 viewpoint{0};

  bool operator==(const Camera&) const = default;
};

struct Material {
  std::string name;
  Where where;  // the entity in the source
  glm::dvec3 ambient{0};
  glm::dvec3 diffuse{0};
  glm::dvec3 specular{0};
  double shininess = 32;

  bool operator==(const Material&) const = default;
};

struct Light {
  std::string name;
  Where where;  // the entity in the source
  glm::dvec3 location{0};
  glm::dvec3 emissivity{1};

  bool operator==(const Light&) const = default;
};

struct Sphere {
  std::string name;
  Where where;  // the entity in the source
  glm::dvec3 center{0};
  double radius = 1;
  int material = 0;

  bool operator==(const Sphere&) const = default;
};

struct Plane {
  std::string name;
  Where where;  // the entity in the source
  glm::dvec3 normal{0, 1, 0};  // as written (not unit)
  glm::dvec3 point{0};
  int material = 0;

  bool operator==(const Plane&) const = default;
};

struct Scene {
  std::vector<Camera> cameras;
  std::vector<Material> materials;
  std::vector<Light> lights;
  std::vector<Sphere> spheres;
  std::vector<Plane> planes;
  OptionSet render;  // options the scene file carries

  // Index of the camera named `name` (first when empty), or nullopt.
  std::optional<int> find_camera(std::string_view name) const;

  // Exact equality, names and source positions included.
  bool operator==(const Scene&) const = default;
};

// Checks all rules of the format (SPEC §1) and builds the scene. Every problem found is
// added to `diags`; returns nullopt when there was any error.
std::optional<Scene> build_scene(const SceneDesc& desc, Diagnostics& diags);

}  // namespace rayfarm
