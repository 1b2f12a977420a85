// Float-to-integer conversions that cannot overflow: the index of a texel or a tile comes
// from coordinates that may be huge or not finite, and an out-of-range conversion is
// undefined behaviour in C++.
#pragma once

#include <cmath>
#include <limits>

namespace rayfarm {

// v truncated toward zero, saturated to the range of int; NaN gives 0.
template <class F>
inline int saturating_trunc(F v) {
  constexpr F kMax = static_cast<F>(std::numeric_limits<int>::max() / 2);
  if (!(v == v)) return 0;
  if (v >= kMax) return static_cast<int>(kMax);
  if (v <= -kMax) return -static_cast<int>(kMax);
  return static_cast<int>(v);
}

}  // namespace rayfarm
