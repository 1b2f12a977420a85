// A checked scene with every default applied that does not depend on the profile: what the
// renderer, the linter and the POV-Ray exporter work from. Built only from a SceneDesc
// without errors.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include <glm/vec3.hpp>

#include "rayfarm/diagnostic.h"
#include "rayfarm/image.h"
#include "rayfarm/image_io.h"
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
  std::optional<double> shininess;  // absent: the profile's default (lecture 32, cpsc102 none)
  double transparency = 0;          // 0 opaque .. 1 clear

  bool operator==(const Material&) const = default;
};

// An image file a scene names. The scene holds its path; the pixels come from whoever loads
// the scene (load_scene's resolver), never from core opening files itself.
struct Texture {
  std::string name;  // empty for a texname that is a path with no texture entity
  Where where;
  std::string path;  // as written, relative to the model file
  Where path_where;
  std::shared_ptr<const Image> image;  // null until resolved

  bool operator==(const Texture& o) const {
    return name == o.name && where == o.where && path == o.path && path_where == o.path_where &&
           (image == o.image || (image && o.image && *image == *o.image));
  }
};

// A plane's rectangle: the plane hit is inside when 0 <= u <= width and 0 <= v <= height in
// the frame whose u axis is xdir projected into the plane and whose origin is `point`.
struct Window {
  glm::dvec3 xdir{1, 0, 0};
  double width = 0;
  double height = 0;

  bool operator==(const Window&) const = default;
};

enum class LightKind { point, spot, projector };

struct Light {
  std::string name;
  Where where;  // the entity in the source
  LightKind kind = LightKind::point;
  glm::dvec3 location{0};
  glm::dvec3 emissivity{1};
  // spotlight: lights points within `theta` degrees of the direction towards `aim`
  glm::dvec3 aim{0};
  double theta = 0;
  // projector: a slide in the plane (normal, point) filters the light
  glm::dvec3 normal{0, 0, 1};
  glm::dvec3 point{0};
  Window window;
  int texture = -1;
  int mode = 0;

  bool operator==(const Light&) const = default;
};

struct Sphere {
  glm::dvec3 center{0};
  double radius = 1;
  bool operator==(const Sphere&) const = default;
};

struct Plane {
  glm::dvec3 normal{0, 1, 0};  // as written (not unit)
  glm::dvec3 point{0};
  bool operator==(const Plane&) const = default;
};

struct FinitePlane {  // fplane
  Plane plane;
  Window window;
  bool operator==(const FinitePlane&) const = default;
};

struct TiledPlane {  // tiled_plane: squares alternating between two materials
  Plane plane;
  Window tile;              // xdir and one tile's size
  bool world_xz = false;    // the 2009 form (`dimension`, no xdir): squares on world x and z
  int alt_material = 0;
  bool operator==(const TiledPlane&) const = default;
};

struct TexPlane {  // texplane: a finite plane with an image on it
  Plane plane;
  Window window;
  int texture = 0;
  int mode = 0;  // 0: stretched over the window; 1: tiled, one texel per pixel of world size
  bool operator==(const TexPlane&) const = default;
};

struct Triangle {  // triangle, or the 2009 tri
  std::array<glm::dvec3, 3> vertex{};
  // The plane written with the triangle (the vertices are projected into it); none: the
  // plane through the vertices.
  std::optional<Plane> plane;
  bool operator==(const Triangle&) const = default;
};

struct Revsurf {  // a surface of revolution with one of the course's profiles
  int surfer = 1;
  glm::dvec3 base{0};
  glm::dvec3 direction{0, 1, 0};  // as written (not unit)
  double height = 1;
  bool operator==(const Revsurf&) const = default;
};

// A shape kept out of line, so that objects stay small for the spheres and planes a scene
// has by the hundred thousand (their memory is most of a large scene's load time). Shared
// and immutable; compares by value.
template <class T>
class Boxed {
 public:
  Boxed(T value) : p_(std::make_shared<const T>(std::move(value))) {}  // NOLINT: implicit on purpose
  const T& operator*() const { return *p_; }
  const T* get() const { return p_.get(); }
  bool operator==(const Boxed& o) const { return *p_ == *o.p_; }

 private:
  std::shared_ptr<const T> p_;
};

using Shape = std::variant<Sphere, Plane, Boxed<FinitePlane>, Boxed<TiledPlane>, Boxed<TexPlane>,
                           Boxed<Triangle>, Boxed<Revsurf>>;

// Calls f with the shape itself, whichever way it is kept.
template <class F>
decltype(auto) visit_shape(F&& f, const Shape& shape) {
  return std::visit(
      [&](const auto& s) -> decltype(auto) {
        if constexpr (requires { s.get(); }) return f(*s);
        else return f(s);
      },
      shape);
}

// The largest magnitude among a shape's positions and sizes (directions, normalised before
// use, are left out): what decides whether single precision can hold its arithmetic.
double largest_magnitude(const Shape& shape);
// The same for a light: its location, aim, and a projector's slide.
double largest_magnitude(const Light& light);

struct Object {
  std::string name;
  Where where;  // the entity in the source
  EntityKind kind = EntityKind::sphere;
  int material = 0;
  Shape shape;

  template <class S>
  const S* as() const {
    if constexpr (std::is_same_v<S, Sphere> || std::is_same_v<S, Plane>) {
      return std::get_if<S>(&shape);
    } else {
      const Boxed<S>* b = std::get_if<Boxed<S>>(&shape);
      return b ? b->get() : nullptr;
    }
  }
  bool operator==(const Object&) const = default;
};

struct Scene {
  std::vector<Camera> cameras;
  std::vector<Material> materials;
  std::vector<Texture> textures;
  std::vector<Light> lights;
  std::vector<Object> objects;  // in the order of the file
  OptionSet render;  // options the scene file carries

  // Index of the camera named `name` (first when empty), or nullopt.
  std::optional<int> find_camera(std::string_view name) const;
  // The cameras a message lists when a name finds none: "first, second", and how many have
  // no name ("b; 2 unnamed": those are chosen only as the first, the default).
  std::string camera_names() const;
  // How many objects have shape S.
  template <class S>
  std::size_t count() const {
    std::size_t n = 0;
    for (const Object& o : objects) n += o.as<S>() != nullptr;
    return n;
  }

  // Exact equality, names and source positions included.
  bool operator==(const Scene&) const = default;
};

// Reads a texture file the scene names (`path` as written in it); returns its bytes, or
// nullopt with `error` set. The CLI reads files beside the model file; the server serves
// only what the request uploaded.
class ResourceResolver {
 public:
  virtual ~ResourceResolver() = default;
  virtual std::optional<std::string> read(const std::string& path, std::string& error) const = 0;
  // The most pixels a texture may have, by its header, before anything is decoded: a server
  // takes none larger than the images it renders (a 200 KB PNG can declare 8192 x 8192).
  virtual long long max_pixels() const { return kMaxDecodePixels; }
};

// Checks all rules of the format and builds the scene. Every problem found is added to
// `diags`; returns nullopt when there was any error.
std::optional<Scene> build_scene(const SceneDesc& desc, Diagnostics& diags);

// Decodes every texture of `scene` through `resolver`; reports each one that cannot be read
// or decoded at its place. Returns false on any error.
bool resolve_textures(Scene& scene, const ResourceResolver& resolver, Diagnostics& diags);

}  // namespace rayfarm
