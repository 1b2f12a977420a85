// A sphere in double precision, already widened by the rounding margin of the tracer's
// sphere test: what the conservative culling structures (screen bins, light buffers) are
// built from; and what else those two builders share.
#pragma once

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

// Indices 0 .. n-1 ordered by `near` ascending, ties by index: a stable radix sort on the
// floats' bits (three passes), much cheaper than sorting every bucket. Filling buckets in
// this order leaves each one nearest first, the same order on every build.
inline std::vector<std::int32_t> order_by_near(const std::vector<float>& near) {
  const std::size_t n = near.size();
  std::vector<std::uint32_t> key(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t b = __builtin_bit_cast(std::uint32_t, near[i] == 0 ? 0.0f : near[i]);
    key[i] = (b & 0x80000000u) ? ~b : b | 0x80000000u;  // unsigned order = float order
  }
  std::vector<std::int32_t> order(n), other(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = static_cast<std::int32_t>(i);
  for (int shift = 0; shift < 32; shift += 11) {
    std::uint32_t count[2049] = {};
    for (std::size_t i = 0; i < n; ++i) ++count[((key[i] >> shift) & 2047u) + 1];
    for (int d = 0; d < 2048; ++d) count[d + 1] += count[d];
    for (std::int32_t i : order) other[count[(key[i] >> shift) & 2047u]++] = i;
    order.swap(other);
  }
  return order;
}

}  // namespace rayfarm
