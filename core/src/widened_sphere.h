// A sphere in double precision, already widened by the rounding margin of the tracer's
// sphere test: what the conservative culling structures (screen bins, light buffers) are
// built from.
#pragma once

#include <cmath>
#include <glm/vec3.hpp>
#include <limits>

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

}  // namespace rayfarm
