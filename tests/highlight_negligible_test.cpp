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
  bound_highlight(m);  // as prepare_scene does
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
    const T shininess = rng.chance(0.5)
                            ? static_cast<T>(16 << rng.below(4))  // 16..128
                            : static_cast<T>(std::exp(rng.in(std::log(0.5), std::log(1e4))));
    Vec3<T> specular;
    for (int c = 0; c < 3; ++c)
      specular[c] = rng.chance(0.2) ? T(0) : magnitude(-40) * T(rng.in(0, 4));
    PreparedMaterial<T> m = material(specular, shininess);
    T b = rng.chance(0.1) ? T(0) : magnitude(rng.chance(0.5) ? -3 : -200);
    Vec3<T> term;
    for (int c = 0; c < 3; ++c) term[c] = magnitude(rng.chance(0.8) ? -4 : -1100);
    if (rng.chance(0.05)) term[rng.below(3)] = -T(0);  // a diffuse of -0 is valid
    if (rng.chance(0.3)) {
      // At the edge of the bound: a base just under a power of two, a whole shininess, and a
      // specular just under the largest power of two the bound lets through for a term in
      // [2^t, 2^(t+1)): the highlight then adds about a sixteenth of the term's ulp.
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
  // Bases of 1 and above (a dot product of unit vectors rounds up to them).
  EXPECT_FALSE(highlight_negligible(material<double>(Vec3<double>(0.3), 64.0), 1.0, term));
  EXPECT_FALSE(highlight_negligible(material<double>(Vec3<double>(0.3), 64.0),
                                    std::nextafter(1.0, 2.0), term));
  // A channel of -0 turns +0 with +0 added: not left out, whether the base is 0 or the
  // channel's specular is.
  const Vec3<double> minus_zero(0.5, -0.0, 0.5);
  EXPECT_FALSE(highlight_negligible(material<double>(Vec3<double>(0.3), 64.0), 0.0, minus_zero));
  EXPECT_FALSE(
      highlight_negligible(material<double>(Vec3<double>(0.3, 0, 0.3), 64.0), 1e-3, minus_zero));
  // And the cases that are left out: a base of 0, and a small one at a high shininess.
  EXPECT_TRUE(highlight_negligible(material<double>(Vec3<double>(0.3), 64.0), 0.0, term));
  EXPECT_TRUE(highlight_negligible(material<double>(Vec3<double>(0.3), 128.0), 0.4, term));
}

// The bound's own edge, pinned: one power of two of specular more and the answer is no.
template <class T>
void expect_edge(T b, T shininess, T term, T specular_in, T specular_out) {
  const Vec3<T> t(term);
  const PreparedMaterial<T> in = material(Vec3<T>(specular_in), shininess);
  ASSERT_TRUE(highlight_negligible(in, b, t));
  const Vec3<T> sum = t + in.specular * std::pow(b, shininess);
  EXPECT_EQ(__builtin_memcmp(&sum, &t, sizeof sum), 0);
  EXPECT_FALSE(highlight_negligible(material(Vec3<T>(specular_out), shininess), b, t));
}

TEST(HighlightNegligible, TheEdgeOfTheBoundIsWhereTheProofPutsIt) {
  // b = 1/4, s = 10: the power is 2^-20 and bounded by 2^-9; a term of 1 admits 2^(E-9)
  // up to a quarter ulp, 2^-54 (2^-25 in float).
  expect_edge<double>(0.25, 10, 1, 0x1p-46, 0x1p-45);
  expect_edge<float>(0.25f, 10, 1, 0x1p-17f, 0x1p-16f);
  // Where the power underflows to the least subnormal (the bound's floor, which the library's
  // power reaches here), only a huge specular brings the product back to a quarter ulp of
  // 1 + ulp: the largest specular below 2^1020 is left out, 2^1020 is not.
  expect_edge<double>(0x1.fffffffffffffp-2, 1074.25, 1 + 0x1p-52, std::nextafter(0x1p1020, 0.0),
                      0x1p1020);
  expect_edge<float>(0x1.fffffep-2f, 149.25f, 1 + 0x1p-23f, std::nextafter(0x1p124f, 0.0f),
                     0x1p124f);
  // Shininess at the extremes: the power is 0 (or the least subnormal) or all but 1.
  for (double s : {1e300, std::numeric_limits<double>::max(), 5e-324, 1e-300}) {
    SCOPED_TRACE(s);
    const Vec3<double> t(0.75);
    const PreparedMaterial<double> m = material(Vec3<double>(0.5), s);
    if (highlight_negligible(m, 0.25, t)) {
      const Vec3<double> sum = t + m.specular * std::pow(0.25, s);
      EXPECT_EQ(__builtin_memcmp(&sum, &t, sizeof sum), 0);
    }
  }
  EXPECT_TRUE(highlight_negligible(material(Vec3<double>(0.5), 1e300), 0.25, Vec3<double>(0.75)));
  EXPECT_FALSE(highlight_negligible(material(Vec3<double>(0.5), 5e-324), 0.25, Vec3<double>(0.75)));
  EXPECT_TRUE(highlight_negligible(material(Vec3<float>(0.5f), std::numeric_limits<float>::max()),
                                   0.25f, Vec3<float>(0.75f)));
}

}  // namespace
}  // namespace rayfarm
