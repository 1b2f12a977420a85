// Rays cast by kind, for the render's statistics.
#pragma once

#include <cstdint>

namespace rayfarm {

struct RayCounts {
  std::uint64_t primary = 0;
  std::uint64_t shadow = 0;
  std::uint64_t reflection = 0;  // every secondary ray: reflected and transmitted
};

}  // namespace rayfarm
