// Helpers shared by the tests: load a scene from text, render it, read a pixel.
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "rayfarm/image_io.h"
#include "rayfarm/load.h"
#include "rayfarm/render.h"

namespace rayfarm::test {

// The lecture scene (scenes/cho.txt), the one scene every module is checked against.
inline std::string lecture_scene() {
  std::ifstream in(RAYFARM_SOURCE_DIR "/scenes/cho.txt", std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Texture files beside a scene file, as the command line reads them.
class FilesBeside final : public ResourceResolver {
 public:
  explicit FilesBeside(std::string dir) : dir_(std::move(dir)) {}
  std::optional<std::string> read(const std::string& path, std::string& error) const override {
    std::ifstream in(dir_ + "/" + path, std::ios::binary);
    if (!in) {
      error = "no such file";
      return std::nullopt;
    }
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }

 private:
  std::string dir_;
};

// A scene file loaded with its textures.
inline LoadedScene load_file(const std::string& path, std::string* text_out = nullptr) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  const std::string text = s.str();
  if (text_out) *text_out = text;
  const FilesBeside textures(path.substr(0, path.find_last_of('/')));
  return load_scene(text, LoadDetail::full, &textures);
}

// A stack of ten parallel planes that reflect and let through everything: every ray that
// meets one goes on both ways into the stack, doubling the rays at every bounce.
inline std::string translucent_mirror_stack() {
  std::string text =
      "camera c { pixeldim 4 3 worlddim 8 6 viewpoint 4 3 6 }\n"
      "material glassy_mirror { ambient 1 1 1 diffuse 1 1 1 specular 1 transparency 1 }\n"
      "light l { location 4 3 2 }\n";
  for (int i = 1; i <= 10; ++i)
    text += "plane p" + std::to_string(i) + " { material glassy_mirror normal 0 0 1 point 0 0 -" +
            std::to_string(i) + " }\n";
  return text;
}

inline Scene scene_from(const std::string& text) {
  LoadedScene loaded = load_scene(text);
  std::string errors;
  for (const Diagnostic& d : loaded.diags.items()) errors += format_diagnostic(d, "scene", text);
  EXPECT_TRUE(loaded.scene.has_value()) << errors;
  return loaded.scene ? *loaded.scene : Scene{};
}

// Texture files held in memory (path as the scene writes it -> image), served as PPM bytes
// the way the CLI serves files beside the model file.
class MemoryResolver final : public ResourceResolver {
 public:
  explicit MemoryResolver(std::map<std::string, Image> files) : files_(std::move(files)) {}
  std::optional<std::string> read(const std::string& path, std::string& error) const override {
    auto it = files_.find(path);
    if (it == files_.end()) {
      error = "no such file";
      return std::nullopt;
    }
    const std::vector<unsigned char> bytes = encode_ppm(it->second);
    return std::string(bytes.begin(), bytes.end());
  }

 private:
  std::map<std::string, Image> files_;
};

// A scene whose textures are the given in-memory images.
inline Scene scene_from(const std::string& text, std::map<std::string, Image> files) {
  const MemoryResolver resolver(std::move(files));
  LoadedScene loaded = load_scene(text, LoadDetail::full, &resolver);
  std::string errors;
  for (const Diagnostic& d : loaded.diags.items()) errors += format_diagnostic(d, "scene", text);
  EXPECT_TRUE(loaded.scene.has_value()) << errors;
  return loaded.scene ? *loaded.scene : Scene{};
}

inline Image render(const Scene& scene, RenderOptions options = {}, int threads = 1,
                    RenderStats* stats = nullptr) {
  std::string error;
  Image image = render_image(scene, options, threads, stats, {}, nullptr, &error);
  EXPECT_EQ(error, "");
  return image;
}

// Pixel at image column x, image row r (row 0 = top).
inline std::array<int, 3> pixel(const Image& image, int x, int r) {
  const std::uint8_t* p = image.row(r) + x * 3;
  return {p[0], p[1], p[2]};
}

// The i-th object of shape S, in file order, and its shape.
template <class S>
const Object& nth(const Scene& scene, size_t i) {
  for (const Object& o : scene.objects)
    if (o.as<S>() && i-- == 0) return o;
  throw std::out_of_range("no such object");
}
template <class S>
const S& shape(const Scene& scene, size_t i) {
  return *nth<S>(scene, i).template as<S>();
}

// Adds an object of the given shape (tests that build scenes by hand).
template <class S>
Object& add(Scene& scene, const S& shape, int material = 0, std::string name = {}) {
  Object& o = scene.objects.emplace_back();
  o.name = std::move(name);
  o.kind = std::is_same_v<S, Sphere> ? EntityKind::sphere : EntityKind::plane;
  o.material = material;
  o.shape = shape;
  return o;
}

// The byte rounding=nearest gives for a channel value (docs/rendering.md#samples-and-bytes).
inline int byte_of(long double c) {
  if (c < 0) c = 0;
  if (c > 1) c = 1;
  return static_cast<int>(std::floor(255 * c + 0.5L));
}

// Two checked scenes are the same, entity by entity and value by value.
inline void expect_same_scene(const Scene& a, const Scene& b) {
  ASSERT_EQ(a.cameras.size(), b.cameras.size());
  for (size_t i = 0; i < a.cameras.size(); ++i) {
    EXPECT_EQ(a.cameras[i].name, b.cameras[i].name);
    EXPECT_EQ(a.cameras[i].width, b.cameras[i].width);
    EXPECT_EQ(a.cameras[i].height, b.cameras[i].height);
    EXPECT_EQ(a.cameras[i].world_width, b.cameras[i].world_width);
    EXPECT_EQ(a.cameras[i].world_height, b.cameras[i].world_height);
    EXPECT_EQ(a.cameras[i].viewpoint, b.cameras[i].viewpoint);
  }
  ASSERT_EQ(a.materials.size(), b.materials.size());
  for (size_t i = 0; i < a.materials.size(); ++i) {
    EXPECT_EQ(a.materials[i].name, b.materials[i].name);
    EXPECT_EQ(a.materials[i].ambient, b.materials[i].ambient);
    EXPECT_EQ(a.materials[i].diffuse, b.materials[i].diffuse);
    EXPECT_EQ(a.materials[i].specular, b.materials[i].specular);
    EXPECT_EQ(a.materials[i].shininess, b.materials[i].shininess);
    EXPECT_EQ(a.materials[i].transparency, b.materials[i].transparency);
  }
  ASSERT_EQ(a.lights.size(), b.lights.size());
  for (size_t i = 0; i < a.lights.size(); ++i) {
    EXPECT_EQ(a.lights[i].name, b.lights[i].name);
    EXPECT_EQ(a.lights[i].location, b.lights[i].location);
    EXPECT_EQ(a.lights[i].emissivity, b.lights[i].emissivity);
    EXPECT_EQ(a.lights[i].kind, b.lights[i].kind);
    EXPECT_EQ(a.lights[i].aim, b.lights[i].aim);
    EXPECT_EQ(a.lights[i].theta, b.lights[i].theta);
    EXPECT_EQ(a.lights[i].normal, b.lights[i].normal);
    EXPECT_EQ(a.lights[i].point, b.lights[i].point);
    EXPECT_TRUE(a.lights[i].window == b.lights[i].window);
    EXPECT_EQ(a.lights[i].texture, b.lights[i].texture);
    EXPECT_EQ(a.lights[i].mode, b.lights[i].mode);
  }
  ASSERT_EQ(a.textures.size(), b.textures.size());
  for (size_t i = 0; i < a.textures.size(); ++i) {
    EXPECT_EQ(a.textures[i].name, b.textures[i].name);
    EXPECT_EQ(a.textures[i].path, b.textures[i].path);
  }
  ASSERT_EQ(a.objects.size(), b.objects.size());
  for (size_t i = 0; i < a.objects.size(); ++i) {
    EXPECT_EQ(a.objects[i].name, b.objects[i].name);
    EXPECT_EQ(a.objects[i].kind, b.objects[i].kind);
    EXPECT_EQ(a.objects[i].material, b.objects[i].material);
    EXPECT_TRUE(a.objects[i].shape == b.objects[i].shape) << "object " << i;
  }
}

}  // namespace rayfarm::test
