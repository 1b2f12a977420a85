// The highlight's power is left out only where adding it could not change a bit of the term
// (highlight_negligible, render/tracer.h): wherever it says so, term + specular · pow(b, s)
// is term again, channel by channel, in both precisions, over bases and terms from subnormal
// to 1, shininess from 1/2 to 10^4, specular channels of 0 and of every size; and it does say
// so often at the shininess of the benchmark scenes.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "random_scene.h"
#include "render/tracer.h"

namespace rayfarm {
namespace {

template <class T>
PreparedMaterial<T> material(const Vec3<T>& specular, T shininess) {
  PreparedMaterial<T> m{};
  m.specular = specular;
  m.shininess = shininess;
  m.highlight_bounded = shininess > 0 && std::isfinite(shininess);
  for (int c = 0; c < 3; ++c) {
    m.highlight_bounded = m.highlight_bounded && std::isfinite(specular[c]);
    int e = 0;
    std::frexp(specular[c], &e);
    m.specular_exp[c] = specular[c] == 0 ? PreparedMaterial<T>::kZeroSpecular : e;
  }
  return m;
}

template <class T>
void expect_left_out_only_where_nothing_changes() {
  test::Rng rng(sizeof(T) == 8 ? 71 : 72);
  const T tiny = std::numeric_limits<T>::denorm_min();
  auto magnitude = [&](double lo_exp) {  // 2^[lo_exp, 0], at times 0 or the least subnormal
    if (rng.chance(0.05)) return T(0);
    if (rng.chance(0.03)) return tiny;
    return static_cast<T>(std::exp2(rng.in(lo_exp, 0)));
  };
  int left_out = 0, positive = 0, cases = 0;
  for (int i = 0; i < 400000; ++i) {
    const T shininess = rng.chance(0.5) ? static_cast<T>(16 << rng.below(4))  // 16..128
                                        : static_cast<T>(std::exp(rng.in(std::log(0.5), std::log(1e4))));
    Vec3<T> specular;
    for (int c = 0; c < 3; ++c) specular[c] = rng.chance(0.2) ? T(0) : magnitude(-40) * T(rng.in(0, 4));
    PreparedMaterial<T> m = material(specular, shininess);
    T b = rng.chance(0.1) ? T(0) : magnitude(rng.chance(0.5) ? -3 : -200);
    Vec3<T> term;
    for (int c = 0; c < 3; ++c) term[c] = magnitude(rng.chance(0.8) ? -4 : -1100);
    if (rng.chance(0.3)) {
      // At the edge of the bound: a base just under a power of two, a whole shininess, and a
      // specular just under the largest power of two the bound lets through for a term in
      // [2^t, 2^(t+1)): the highlight then adds about an eighth of the term's ulp.
      const int g1 = -1 - rng.below(6), s = 1 + rng.below(40), t = -rng.below(8);
      b = std::nextafter(static_cast<T>(std::ldexp(1.0, g1)), T(0));
      const int e = t - std::numeric_limits<T>::digits - 2 - (g1 * s + 1);
      const T edge = std::nextafter(static_cast<T>(std::ldexp(1.0, e)), T(0));
      for (int c = 0; c < 3; ++c) term[c] = static_cast<T>(std::ldexp(rng.in(1, 2), t));
      m = material(Vec3<T>(edge), static_cast<T>(s));
    }
    ++cases;
    positive += b > 0;
    if (!highlight_negligible(m, b, term)) continue;
    ++left_out;
    const Vec3<T> sum = term + m.specular * std::pow(b, m.shininess);
    for (int c = 0; c < 3; ++c)
      ASSERT_EQ(__builtin_memcmp(&sum[c], &term[c], sizeof(T)), 0)
          << "channel " << c << " base " << b << " shininess " << shininess << " specular "
          << specular[c] << " term " << term[c];
  }
  EXPECT_GT(left_out, cases / 4);
  EXPECT_LT(left_out, cases - positive / 4);
}

TEST(HighlightNegligible, LeftOutOnlyWhereTheSumIsTheTermAgain) {
  expect_left_out_only_where_nothing_changes<double>();
  expect_left_out_only_where_nothing_changes<float>();
}

TEST(HighlightNegligible, NeverWhereTheBoundDoesNotHold) {
  const Vec3<double> term(0.5);
  // A power that is not below 1 (shininess 0 or less), and specular channels with no bound.
  EXPECT_FALSE(highlight_negligible(material<double>(Vec3<double>(0.3), 0.0), 1e-30, term));
  EXPECT_FALSE(highlight_negligible(material<double>(Vec3<double>(0.3), -2.0), 1e-30, term));
  EXPECT_FALSE(highlight_negligible(material<double>(Vec3<double>(0.3), NAN), 1e-30, term));
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(highlight_negligible(material<double>(Vec3<double>(inf, 0, 0), 64.0), 0.0, term));
  // A channel the highlight alone lights, and bases at and above 1/2 with a modest shininess.
  EXPECT_FALSE(highlight_negligible(material<double>(Vec3<double>(0.3), 64.0), 1e-3,
                                    Vec3<double>(0.5, 0, 0.5)));
  EXPECT_FALSE(highlight_negligible(material<double>(Vec3<double>(0.3), 16.0), 0.5, term));
  // And the cases that are left out: a base of 0, and a small one at a high shininess.
  EXPECT_TRUE(highlight_negligible(material<double>(Vec3<double>(0.3), 64.0), 0.0, term));
  EXPECT_TRUE(highlight_negligible(material<double>(Vec3<double>(0.3), 128.0), 0.4, term));
}

}  // namespace
}  // namespace rayfarm
