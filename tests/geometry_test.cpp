// Seeded property tests of ray/sphere and ray/plane intersection, and of the tracer's rule
// that a secondary ray never hits the point it leaves from.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "rayfarm/intersect.h"
#include "render/tracer.h"

namespace rayfarm {
namespace {

using V = Vec3<double>;

struct RandomRays {
  std::mt19937_64 rng{12345};
  std::uniform_real_distribution<double> unit{-1, 1};
  V direction() {
    for (;;) {
      V v{unit(rng), unit(rng), unit(rng)};
      double l = glm::length(v);
      if (l > 0.1 && l <= 1) return v / l;
    }
  }
  double in(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
};

TEST(RaySphere, HitsLieOnTheSurfaceWithUnitNormals) {
  RandomRays r;
  for (int i = 0; i < 2000; ++i) {
    V centre{r.in(-100, 100), r.in(-100, 100), r.in(-100, 100)};
    double radius = std::exp(r.in(std::log(1e-3), std::log(1e3)));
    // Aim from outside at a random point of the sphere.
    V target = centre + radius * 0.999 * r.direction();
    V origin = centre + radius * r.in(1.5, 50) * r.direction();
    V dir = glm::normalize(target - origin);
    auto roots = sphere_roots(origin, dir, centre, radius);
    ASSERT_TRUE(roots) << "iteration " << i;
    EXPECT_LE(roots->near, roots->far);
    for (double t : {roots->near, roots->far}) {
      V p = origin + t * dir;
      EXPECT_NEAR(glm::length(p - centre), radius, 1e-9 * (radius + glm::length(origin - centre)));
      V n = glm::normalize(p - centre);
      EXPECT_NEAR(glm::length(n), 1.0, 1e-12);
    }
    EXPECT_GT(roots->near, 0) << "the ray starts outside, both roots lie ahead";
  }
}

TEST(RaySphere, RayFromInsideHasOneRootBehindAndOneAhead) {
  RandomRays r;
  for (int i = 0; i < 1000; ++i) {
    V centre{r.in(-10, 10), r.in(-10, 10), r.in(-10, 10)};
    double radius = r.in(0.5, 20);
    V origin = centre + radius * r.in(0, 0.95) * r.direction();
    auto roots = sphere_roots(origin, r.direction(), centre, radius);
    ASSERT_TRUE(roots);
    EXPECT_LT(roots->near, 0);
    EXPECT_GT(roots->far, 0);
  }
}

TEST(RaySphere, TangentRayTouchesOnceAndMissAboveIt) {
  V centre{0, 0, -10};
  double radius = 2;
  // Rays along -z at height y: tangent at y = radius.
  auto tangent = sphere_roots(V{0, radius, 0}, V{0, 0, -1}, centre, radius);
  ASSERT_TRUE(tangent);
  EXPECT_NEAR(tangent->near, 10, 1e-6);
  EXPECT_NEAR(tangent->far, 10, 1e-6);
  EXPECT_FALSE(sphere_roots(V{0, radius * (1 + 1e-9), 0}, V{0, 0, -1}, centre, radius));
  auto grazing = sphere_roots(V{0, radius * (1 - 1e-9), 0}, V{0, 0, -1}, centre, radius);
  ASSERT_TRUE(grazing);
  EXPECT_LT(grazing->far - grazing->near, 1e-3);
}

TEST(RaySphere, StableFormFindsTinyFarSpheresInFloatWhereTheTextbookFormFails) {
  // A sphere of radius 20 seen from 100,000 units away: in float the textbook quadratic loses
  // r^2 next to |o - c|^2 and its discriminant cancels to zero or below; the stable form keeps it.
  using F = Vec3<float>;
  const F eye{4, 3, 5}, centre{4.5f, 3.25f, -100000};
  int stable_hits = 0, naive_hits = 0, total = 0;
  for (int i = -20; i <= 20; ++i)
    for (int j = -20; j <= 20; ++j) {
      if (i * i + j * j > 21 * 21) continue;  // offsets of 0.9 i: well inside the radius
      F dir = glm::normalize(centre + F{0.9f * i, 0.9f * j, 0} - eye);
      ++total;
      stable_hits += sphere_roots(eye, dir, centre, 20.0f).has_value();
      naive_hits += sphere_roots_naive(eye, dir, centre, 20.0f).has_value();
    }
  EXPECT_EQ(stable_hits, total);
  EXPECT_LT(naive_hits, total / 10);
  // In double both agree.
  auto hit = sphere_roots_naive(Vec3<double>(eye), glm::normalize(Vec3<double>(centre) - Vec3<double>(eye)),
                                Vec3<double>(centre), 20.0);
  EXPECT_TRUE(hit.has_value());
}

TEST(RayPlane, HitsLieOnThePlaneAndParallelRaysMiss) {
  RandomRays r;
  for (int i = 0; i < 2000; ++i) {
    V n = r.direction();
    V point{r.in(-50, 50), r.in(-50, 50), r.in(-50, 50)};
    V origin{r.in(-50, 50), r.in(-50, 50), r.in(-50, 50)};
    V dir = r.direction();
    auto t = plane_distance(origin, dir, n, point);
    if (!t) continue;
    V p = origin + *t * dir;
    EXPECT_NEAR(glm::dot(p - point, n), 0, 1e-9 * (1 + std::abs(*t)));
  }
  EXPECT_FALSE(plane_distance(V{0, 1, 0}, V{1, 0, 0}, V{0, 1, 0}, V{0, 0, 0}));
}

// A scene with one sphere and one plane, prepared in double, for the tracer's own queries.
PreparedScene<double> two_objects(double scale) {
  PreparedScene<double> s;
  s.width = s.height = 1;
  s.max_dist = std::numeric_limits<double>::infinity();
  s.materials.push_back({V(0), V(0), V(0), 32, 0, false, false});
  s.spheres.push_back({V{0, 0, -5} * scale, 1 * scale});
  s.sphere_materials.push_back(0);
  s.planes.push_back({V{0, 1, 0}, V{0, -1, 0} * scale, 0});
  s.planes.back().point_scale = scale;
  return s;
}

TEST(SecondaryRays, LeavingASphereOutsideNeverHitsItAgainAtAnyScale) {
  RandomRays r;
  for (double scale : {1e-6, 1.0, 1e6}) {
    PreparedScene<double> s = two_objects(scale);
    Tracer<double> tracer(s);
    for (int i = 0; i < 500; ++i) {
      V n = r.direction();
      V p = s.spheres[0].centre + s.spheres[0].radius * n;
      V d = r.direction();
      if (glm::dot(d, n) < 0) d = -d;  // leaving the outside
      Hit<double> hit = tracer.closest(p, d, {0, false}, s.max_dist);
      EXPECT_NE(hit.object, 0) << "scale " << scale;
    }
  }
}

TEST(SecondaryRays, LeavingASphereInsideHitsItsFarSide) {
  RandomRays r;
  for (double scale : {1e-6, 1.0, 1e6}) {
    PreparedScene<double> s = two_objects(scale);
    s.planes.clear();
    Tracer<double> tracer(s);
    for (int i = 0; i < 500; ++i) {
      V n = r.direction();
      V p = s.spheres[0].centre + s.spheres[0].radius * n;
      V d = r.direction();
      if (glm::dot(d, n) > 0) d = -d;  // into the sphere
      Hit<double> hit = tracer.closest(p, d, {0, true}, s.max_dist);
      ASSERT_EQ(hit.object, 0) << "scale " << scale;
      // The chord length: 2 r |cos| where cos is between the inward ray and the normal.
      EXPECT_NEAR(hit.t, 2 * s.spheres[0].radius * -glm::dot(d, n), 1e-9 * scale);
    }
  }
}

TEST(SecondaryRays, LeavingAPlaneNeverHitsItAgain) {
  PreparedScene<double> s = two_objects(1);
  Tracer<double> tracer(s);
  RandomRays r;
  for (int i = 0; i < 500; ++i) {
    V p{r.in(-100, 100), -1, r.in(-100, 100)};
    V d = r.direction();
    Hit<double> hit = tracer.closest(p, d, {1, false}, s.max_dist);
    EXPECT_NE(hit.object, 1);
  }
}

// The tiled planes' square parity without fmod (tracer.h tile_parity) decides as the course's
// fmod(ix + iy, 2) rule did, in both forms: for whole sums of either sign and any size, at
// and past the last odd number the precision holds, for -0, infinities and NaN.
template <class T>
void expect_parity_as_fmod(T s) {
  const T r = std::fmod(s, T(2));
  EXPECT_EQ(tile_parity(s) == T(0.5), r == 1 || r == -1) << s;  // plane frame: odd
  EXPECT_EQ(tile_parity(s) != 0, r != 0) << s;                   // 2009 form: odd or not finite
}

template <class T>
void parity_cases() {
  constexpr T kInf = std::numeric_limits<T>::infinity();
  const T big = std::ldexp(T(1), std::numeric_limits<T>::digits);  // 2^53 (2^24 in float)
  for (T s : {T(0), T(-0.0), T(1), T(-1), T(2), T(-2), T(3), T(-3), T(19999), T(-20001),
              big - 1, -(big - 1), big, -big, big + 2, big * 4, std::numeric_limits<T>::max(),
              std::numeric_limits<T>::lowest(), kInf, -kInf,
              std::numeric_limits<T>::quiet_NaN()})
    expect_parity_as_fmod(s);
  // Sums of floors as the tracer forms them, over many magnitudes.
  std::mt19937_64 rng(16);
  std::uniform_real_distribution<double> exponent(-2, 30), unit(-1, 1);
  for (int i = 0; i < 20000; ++i) {
    const T a = std::floor(static_cast<T>(unit(rng) * std::pow(2.0, exponent(rng))));
    const T b = std::floor(static_cast<T>(unit(rng) * std::pow(2.0, exponent(rng))));
    expect_parity_as_fmod(static_cast<T>(a + b));
  }
}

TEST(TiledPlane, SquareParityWithoutFmodDecidesAsFmod) {
  parity_cases<double>();
  parity_cases<float>();
}

}  // namespace
}  // namespace rayfarm
