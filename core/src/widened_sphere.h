// A sphere in double precision, already widened by the rounding margin of the tracer's
// sphere test: what the conservative culling structures (screen bins, light buffers) are
// built from; and what else those two builders share.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <glm/vec3.hpp>
#include <limits>
#include <vector>

namespace rayfarm {

struct WidenedSphere {
  glm::dvec3 centre;
  double radius;
};

// The largest float not above x: a bound stored as float stays a bound.
inline float float_down(double x) {
  constexpr double kMax = std::numeric_limits<float>::max();
  if (!(x >= -kMax)) return -std::numeric_limits<float>::infinity();  // NaN too: no bound
  if (x > kMax) return std::numeric_limits<float>::max();
  float f = static_cast<float>(x);
  if (static_cast<double>(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

// Sorts each bucket [start[b], start[b + 1]) of entries (with `near` and `sphere`) nearest
// first, ties by sphere, so that every build lists them in the same order.
template <class Entry>
void sort_buckets_nearest_first(std::vector<Entry>& entries,
                                const std::vector<std::uint32_t>& start) {
  for (std::size_t b = 0; b + 1 < start.size(); ++b)
    std::sort(entries.begin() + start[b], entries.begin() + start[b + 1],
              [](const Entry& x, const Entry& y) {
                return x.near < y.near || (x.near == y.near && x.sphere < y.sphere);
              });
}

}  // namespace rayfarm
