// glibc's random() (TYPE_3, the additive feedback generator behind rand() and random()),
// which the reference program's anti-aliasing demos drew their jitter from without seeding
// it (seed 1). Reproduced so that `spp` in the cpsc102 profile samples as that program did.
#pragma once

#include <array>
#include <cstdint>

namespace rayfarm::cpsc102 {

class GlibcRandom {
 public:
  explicit GlibcRandom(std::uint32_t seed = 1) {
    std::int64_t word = seed == 0 ? 1 : seed;
    r_[0] = static_cast<std::uint32_t>(word);
    for (int i = 1; i < 31; ++i) {
      // 16807 * r mod (2^31 - 1) by Schrage's method, as glibc computes it.
      const std::int64_t hi = word / 127773, lo = word % 127773;
      word = 16807 * lo - 2836 * hi;
      if (word < 0) word += 2147483647;
      r_[i] = static_cast<std::uint32_t>(word);
    }
    for (int i = 31; i < 34; ++i) r_[i] = r_[i - 31];
    i_ = 34;
    for (int k = 34; k < 344; ++k) step();
  }

  // The next value of random(): 0 .. 2^31 - 1.
  std::uint32_t next() { return step() >> 1; }

  // Skips n values.
  void discard(std::uint64_t n) {
    for (std::uint64_t k = 0; k < n; ++k) step();
  }

 private:
  // r_i = r_{i-3} + r_{i-31} (mod 2^32) over a ring of the last 34 values.
  std::uint32_t step() {
    const std::uint32_t v = r_[(i_ + 34 - 31) % 34] + r_[(i_ + 34 - 3) % 34];
    r_[i_ % 34] = v;
    i_ = (i_ + 1) % 34 + 34;
    return v;
  }

  std::array<std::uint32_t, 34> r_{};
  unsigned i_ = 0;
};

}  // namespace rayfarm::cpsc102
