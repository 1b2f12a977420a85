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

  // Adds sample c to a pixel channel's sum. The lecture keeps the sum as `sum` plus the
  // compensation `comp` (Neumaier's: exact unless samples far apart in size cancel), so that
  // the mean of equal samples is that sample at any spp: a flat colour such as a background
  // of 0.3 (76.5 levels, a tie) would otherwise round to 76 or 77 by the number of samples.
  // `sum` alone is the plain running sum. cpsc102 sums as the course's program did, in its
  // extended arithmetic.
  void accumulate(double& sum, double& comp, double c) const {
    if (extended) {
      sum = static_cast<double>(static_cast<long double>(sum) + c);
      return;
    }
    const double t = sum + c;
    // (An infinite sum, from an emissivity past the doubles, has no rounding to keep.)
    if (std::isfinite(t)) comp += std::abs(sum) >= std::abs(c) ? (sum - t) + c : (c - t) + sum;
    sum = t;
  }
  // The mean of n samples from their sum: (sum + comp) / n, rounded once (not the rounded
  // sum divided again, which misses the sample itself for one n in ten).
  double mean(double sum, double comp, int n) const {
    if (extended) {
      const double inv = static_cast<double>(1.0L / n);
      return static_cast<double>(static_cast<long double>(sum) * inv);
    }
    const double q = sum / n;
    if (!(std::abs(q) < 0x1p995)) return q;  // infinite, or too large to split below
    // q * n exactly, as p + e (Dekker's product; n < 2^26 needs no split of its own).
    const double p = q * n;
    constexpr double kSplit = 134217729.0;  // 2^27 + 1
    const double big = kSplit * q, qh = big - (big - q), ql = q - qh;
    const double e = (qh * n - p) + ql * n;
    const double rest = ((sum - p) - e) + comp;  // sum - p is exact (Sterbenz)
    return q + rest / n;
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
