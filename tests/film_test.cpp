// A pixel's samples to its byte: the lecture's mean of equal samples is that sample at any
// number of samples (a flat colour keeps its byte whatever the spp), and means in general are
// the exact sum divided once.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "render/film.h"
#include "test_util.h"

namespace rayfarm {
namespace {

TEST(Film, TheMeanOfEqualSamplesIsTheSample) {
  const Film film;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<double> values = {0.1, 0.2, 0.3, 0.7, 0.9, 1.0 / 3, 0.123456789, 1e-300, 1e290};
  for (int i = 0; i < 40; ++i) values.push_back(unit(rng));
  for (double c : values)
    for (int n = 1; n <= 300; ++n) {
      double sum = 0, comp = 0;
      for (int k = 0; k < n; ++k) film.accumulate(sum, comp, c);
      ASSERT_EQ(film.mean(sum, comp, n), c) << "c " << c << ", n " << n;
    }
}

// Against the exact mean (in long double, exact for these few samples of the same binade):
// the mean is the exact one rounded once, to the nearest double.
TEST(Film, TheMeanIsTheExactSumDividedOnce) {
  const Film film;
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> unit(0.5, 1.0);
  int checked = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const int n = 2 + static_cast<int>(rng() % 7);
    double sum = 0, comp = 0;
    long double exact = 0;
    for (int k = 0; k < n; ++k) {
      const double c = unit(rng);
      film.accumulate(sum, comp, c);
      exact += c;  // 53-bit values in [0.5, 1): a sum of at most 8 is exact in 64 bits
    }
    // The double nearest exact / n: of the candidates around it, the one whose product with
    // n is nearest the exact sum (each product is exact in 64 bits: 53 bits times 3).
    const double guess = static_cast<double>(exact / n);
    double nearest = guess;
    for (double candidate : {std::nextafter(guess, 0.0), std::nextafter(guess, 2.0)})
      if (std::abs(exact - static_cast<long double>(candidate) * n) <
          std::abs(exact - static_cast<long double>(nearest) * n))
        nearest = candidate;
    ASSERT_EQ(film.mean(sum, comp, n), nearest) << "n " << n << ", trial " << trial;
    ++checked;
  }
  EXPECT_EQ(checked, 20000);
}

TEST(Film, AFlatBackgroundKeepsItsByteAtAnySpp) {
  const Scene scene = test::scene_from("camera c { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n");
  for (const char* background : {"0.3", "0.1", "0.7", "0.9", "0.5"}) {
    std::vector<std::uint8_t> first;
    for (int spp : {1, 2, 3, 5, 12, 16, 33}) {
      RenderOptions o;
      o.spp = spp;
      ASSERT_FALSE(apply_option(o, "background", background));
      const Image image = test::render(scene, o, 2);
      if (first.empty()) first = image.rgb;
      EXPECT_EQ(image.rgb, first) << "background " << background << ", spp " << spp;
    }
  }
}

}  // namespace
}  // namespace rayfarm
