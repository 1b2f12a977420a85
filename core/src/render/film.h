// From a pixel's samples to its byte: how samples accumulate and how a mean becomes a byte,
// the profile's convention (the lecture rounds in double; the course's program truncated
// an extended-precision product, and summed its anti-aliasing samples in its arithmetic).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "rayfarm/options.h"

namespace rayfarm {

struct Film {
  Rounding rounding = Rounding::nearest;
  bool extended = false;  // cpsc102: sums and the byte in the reference program's arithmetic

  double accumulate(double sum, double c) const {
    return extended ? static_cast<double>(static_cast<long double>(sum) + c) : sum + c;
  }
  double mean(double sum, int n) const {
    if (!extended) return sum / n;
    const double inv = static_cast<double>(1.0L / n);
    return static_cast<double>(static_cast<long double>(sum) * inv);
  }
  // to_byte of n channels, its choices made once.
  void to_bytes(const double* c, std::size_t n, std::uint8_t* out) const {
    if (extended)
      for (std::size_t i = 0; i < n; ++i) out[i] = to_byte(c[i]);
    else if (rounding == Rounding::nearest)
      for (std::size_t i = 0; i < n; ++i) out[i] = nearest(c[i]);
    else
      for (std::size_t i = 0; i < n; ++i) out[i] = to_byte(c[i]);
  }

  static std::uint8_t nearest(double c) {
    c = c > 0 ? (c < 1 ? c : 1.0) : 0.0;
    return static_cast<std::uint8_t>(std::floor(255 * c + 0.5));
  }

  std::uint8_t to_byte(double c) const {
    c = c > 0 ? (c < 1 ? c : 1.0) : 0.0;  // NaN to 0: no NaN reaches a pixel
    if (extended) {
      const long double v = static_cast<long double>(c) * 255;
      return static_cast<std::uint8_t>(rounding == Rounding::truncate ? v : std::floor(v + 0.5L));
    }
    return static_cast<std::uint8_t>(rounding == Rounding::truncate ? std::floor(255 * c)
                                                                    : std::floor(255 * c + 0.5));
  }
};

}  // namespace rayfarm
