// Helpers shared by the tests: load a scene from text, render it, read a pixel.
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

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

inline Scene scene_from(const std::string& text) {
  LoadedScene loaded = load_scene(text);
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

// The byte the spec's step 7 gives for a channel value.
inline int byte_of(long double c) {
  if (c < 0) c = 0;
  if (c > 1) c = 1;
  return static_cast<int>(std::floor(255 * c + 0.5L));
}

}  // namespace rayfarm::test
