// Sample positions within a pixel: stratified and jittered, from a stream seeded by
// (seed, x, y, sample index) only, so any thread order gives the same samples.
#pragma once

#include <cmath>
#include <cstdint>

namespace rayfarm {

inline std::uint64_t mix64(std::uint64_t z) {  // splitmix64 finaliser
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

inline double unit_double(std::uint64_t bits) {  // [0, 1)
  return static_cast<double>(bits >> 11) * 0x1.0p-53;
}

// A bijection of [0, n) chosen by `key` (Kensler, "Correlated Multi-Jittered Sampling",
// 2013): strata are visited in a scrambled order, so any prefix of the samples covers the
// pixel evenly and a render stopped early is not biased to one corner.
inline std::uint32_t permute(std::uint32_t i, std::uint32_t n, std::uint32_t key) {
  std::uint32_t w = n - 1;
  w |= w >> 1;
  w |= w >> 2;
  w |= w >> 4;
  w |= w >> 8;
  w |= w >> 16;
  do {
    i ^= key;
    i *= 0xe170893d;
    i ^= key >> 16;
    i ^= (i & w) >> 4;
    i ^= key >> 8;
    i *= 0x0929eb3f;
    i ^= key >> 23;
    i ^= (i & w) >> 1;
    i *= 1 | key >> 27;
    i *= 0x6935fa69;
    i ^= (i & w) >> 11;
    i *= 0x74dcb303;
    i ^= (i & w) >> 2;
    i *= 0x9e501cc3;
    i ^= (i & w) >> 2;
    i *= 0xc860a3df;
    i &= w;
    i ^= i >> 5;
  } while (i >= n);
  return static_cast<std::uint32_t>((static_cast<std::uint64_t>(i) + key) % n);
}

struct PixelOffset {
  double u;  // [-0.5, 0.5)
  double v;
};

class StratifiedSampler {
 public:
  explicit StratifiedSampler(int spp)
      : cols_(static_cast<std::uint32_t>(std::ceil(std::sqrt(static_cast<double>(spp))))),
        rows_((static_cast<std::uint32_t>(spp) + cols_ - 1) / cols_) {}

  PixelOffset offset(std::uint64_t seed, int x, int y, int sample) const {
    std::uint64_t pixel = mix64(mix64(seed ^ mix64(static_cast<std::uint64_t>(x))) +
                                static_cast<std::uint64_t>(y));
    std::uint32_t cell =
        permute(static_cast<std::uint32_t>(sample), cols_ * rows_, static_cast<std::uint32_t>(pixel));
    std::uint64_t stream = mix64(pixel + static_cast<std::uint64_t>(sample));
    double jx = unit_double(stream);
    double jy = unit_double(mix64(stream));
    return {(static_cast<double>(cell % cols_) + jx) / cols_ - 0.5,
            (static_cast<double>(cell / cols_) + jy) / rows_ - 0.5};
  }

 private:
  std::uint32_t cols_;
  std::uint32_t rows_;
};

}  // namespace rayfarm
