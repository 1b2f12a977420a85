// An 8-bit RGB image, rows top to bottom, as written to PNG/PPM.
#pragma once

#include <cstdint>
#include <vector>

namespace rayfarm {

struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  // width * height * 3, row 0 = top

  Image() = default;
  Image(int w, int h) : width(w), height(h), rgb(static_cast<size_t>(w) * h * 3, 0) {}

  std::uint8_t* row(int r) { return rgb.data() + static_cast<size_t>(r) * width * 3; }
  const std::uint8_t* row(int r) const { return rgb.data() + static_cast<size_t>(r) * width * 3; }
  bool operator==(const Image&) const = default;
};

}  // namespace rayfarm
