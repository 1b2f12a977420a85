// Stability on stiff and extreme scenes (docs/numerics.md), in both precisions: scaled twins,
// float against double, the textbook root form's failures, and root accuracy against long
// double.
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "rayfarm/intersect.h"
#include "rayfarm/stability.h"
#include "test_util.h"

namespace rayfarm {
namespace {

const std::string kExtreme = RAYFARM_SOURCE_DIR "/scenes/extreme/";

Scene load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return test::scene_from(s.str());
}

struct Difference {
  int max_abs = 0;
  double share_off = 0;  // share of channels that differ at all
};

Difference difference(const Image& a, const Image& b) {
  Difference d;
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  if (a.rgb.size() != b.rgb.size()) return {255, 1};
  long long off = 0;
  for (size_t i = 0; i < a.rgb.size(); ++i) {
    int diff = std::abs(a.rgb[i] - b.rgb[i]);
    d.max_abs = std::max(d.max_abs, diff);
    off += diff > 0;
  }
  d.share_off = static_cast<double>(off) / a.rgb.size();
  return d;
}

RenderOptions with(Precision p, int width = 200, int height = 150) {
  RenderOptions o;
  o.precision = p;
  o.width = width;
  o.height = height;
  o.max_depth = 64;
  return o;
}

TEST(ScaledTwins, ImageIsUnchangedWhenTheSceneIsScaledByAMillionEitherWay) {
  Scene lecture = load(RAYFARM_SOURCE_DIR "/scenes/cho.txt");
  for (const char* twin : {"scaled-1e6.txt", "scaled-1e-6.txt"}) {
    SCOPED_TRACE(twin);
    Scene scaled = load(kExtreme + twin);
    Image d0 = test::render(lecture, with(Precision::f64, 400, 300), 2);
    EXPECT_EQ(test::render(scaled, with(Precision::f64, 400, 300), 2), d0) << "double: to the byte";
    Image f0 = test::render(lecture, with(Precision::f32, 400, 300), 2);
    Difference f = difference(test::render(scaled, with(Precision::f32, 400, 300), 2), f0);
    EXPECT_LE(f.max_abs, 1);
    EXPECT_LT(f.share_off, 0.001);
  }
}

// A direction is any numbers, not all zero: one whose square overflows or underflows double
// (a normal of 1e300 or 1e-320, a spotlight aimed 1e200 away) renders as the same direction
// of ordinary length does, in both profiles, instead of vanishing or being refused.
TEST(ScaledTwins, DirectionsOfAnyLengthRenderAsTheUnitOne) {
  auto scene = [](const std::string& normal, const std::string& axis, const std::string& aim,
                  const std::string& xdir) {
    return test::scene_from(
        "camera c { pixeldim 40 30 worlddim 8 6 viewpoint 4 3 5 }\n"
        "material g { ambient 2 2 2 diffuse .8 .8 .8 specular .3 .3 .3 }\n"
        "light l { location 2.5 5 -1.5 emissivity 4 4 4 }\n"
        "spotlight s { location 4 5 -4 point " + aim + " theta 30 emissivity 4 4 4 }\n"
        "plane p { material g normal " + normal + " point 0 0 0 }\n"
        "revsurf r { material g surfer 2 base 2 0 -6 direction " + axis + " height 3 }\n"
        "fplane f { material g normal 0 0 1 point 4 1 -5 xdir " + xdir + " dimensions 2 1 }\n");
  };
  const Scene unit = scene("0 1 0", "0 1 0", "4 -1 -4", "1 0 0");
  for (const Profile profile : {Profile::lecture, Profile::cpsc102}) {
    RenderOptions o;
    o.profile = profile;
    const Image expected = test::render(unit, o);
    for (const auto& [normal, axis, aim, xdir] :
         {std::array<std::string, 4>{"0 1e300 0", "0 1e-320 0", "4 -1e200 -4", "1e-320 0 0"},
          std::array<std::string, 4>{"0 1e-200 0", "0 1e200 0", "4 -1e-200 -4", "1e300 0 0"}}) {
      const Image got = test::render(scene(normal, axis, aim, xdir), o);
      EXPECT_EQ(got.rgb, expected.rgb) << static_cast<int>(profile) << ": normal " << normal << ", axis " << axis
                                       << ", aim " << aim << ", xdir " << xdir;
    }
  }
}

TEST(Precision, FloatAgreesWithDoubleWithinALevelWhereTheStableFormAllowsIt) {
  // Not in this list: huge-close (float cannot place a surface 1e6 from the origin closer
  // than 0.06).
  for (const char* name : {"tiny-far.txt", "eye-inside.txt", "facing-mirrors.txt",
                           "coincident-touching.txt", "light-on-surface.txt",
                           "one-by-one.txt", "one-by-n.txt", "n-by-one.txt", "wide-window.txt",
                           "narrow-window.txt", "tangent-grazing.txt"}) {
    SCOPED_TRACE(name);
    Scene s = load(kExtreme + name);
    RenderOptions d = with(Precision::f64, 0, 0), f = with(Precision::f32, 0, 0);
    Difference diff = difference(test::render(s, f, 2), test::render(s, d, 2));
    long long big = 0;
    Image a = test::render(s, f, 2), b = test::render(s, d, 2);
    for (size_t i = 0; i < a.rgb.size(); ++i) big += std::abs(a.rgb[i] - b.rgb[i]) > 1;
    EXPECT_LE(static_cast<double>(big) / a.rgb.size(), 0.001) << "max " << diff.max_abs;
  }
}

TEST(Precision, EveryExtremeSceneRendersInBothPrecisions) {
  for (auto& entry : std::filesystem::directory_iterator(kExtreme)) {
    if (entry.path().extension() != ".txt") continue;
    SCOPED_TRACE(entry.path().filename().string());
    Scene s = load(entry.path());
    for (Precision p : {Precision::f64, Precision::f32}) {
      RenderOptions o = with(p, 0, 0);
      o.spp = 2;
      RenderStats st;
      Image img = test::render(s, o, 2, &st);
      EXPECT_TRUE(st.finished);
      EXPECT_GT(img.width, 0);
      EXPECT_GE(st.error_estimate, 0);
    }
  }
}

TEST(Surfaces, ACoincidentTwinNeitherShadowsNorSpecklesTheFirstSphere) {
  const std::string base = R"(
    camera c { pixeldim 120 90 worlddim 8 6 viewpoint 4 3 5 }
    material red { ambient 5 1 1 diffuse 0.7 0.1 0.1 specular 0.3 }
    material blue { ambient 1 1 5 diffuse 0.1 0.1 0.7 specular 0.3 }
    material floor { ambient 2 diffuse 0.5 specular 0.2 }
    light l { location 4 8 2 emissivity 6 }
    sphere one { material red center 3 1 -5 radius 1 }
    plane floor { material floor normal 0 1 0 point 0 0 0 }
  )";
  {
    Scene alone = test::scene_from(base);
    Scene twinned = test::scene_from(
        base + "sphere two { material blue center 3 1 -5 radius 1 }\n"
                       "plane floor2 { material red normal 0 1 0 point 0 0 0 }\n");
    for (Precision p : {Precision::f64, Precision::f32}) {
      RenderOptions o;
      o.precision = p;
      EXPECT_EQ(test::render(twinned, o, 2), test::render(alone, o, 2))
          << "a coincident sphere and plane (later in the file) must change nothing";
    }
  }
}

TEST(Surfaces, ALightOnASurfaceLightsItsSurroundingsEvenly) {
  Scene s = load(kExtreme + "light-on-surface.txt");
  Image img = test::render(s, with(Precision::f64, 160, 120), 2);
  // The floor's bottom rows are lit smoothly: neighbouring pixels differ by a few levels, not
  // by the on/off speckle of a light whose side is decided by rounding.
  int jumps = 0;
  for (int r = 100; r < 120; ++r)
    for (int x = 1; x < 160; ++x)
      jumps += std::abs(test::pixel(img, x, r)[0] - test::pixel(img, x - 1, r)[0]) > 8;
  EXPECT_EQ(jumps, 0);
}

TEST(RootForms, TextbookFormInFloatLosesTheFarSphereAndTheStableFormKeepsIt) {
  Scene s = load(kExtreme + "tiny-far.txt");
  RenderOptions o;
  RootErrors naive = root_errors(s, o, RootForm::naive, Precision::f32);
  RootErrors stable = root_errors(s, o, RootForm::stable, Precision::f32);
  ASSERT_GT(stable.reference_hits, 1000);
  EXPECT_GT(naive.wrong_hit_miss, naive.reference_hits * 9 / 10);
  EXPECT_EQ(stable.wrong_hit_miss, 0);
  EXPECT_LT(stable.max_relative_t_error, 1e-6);
  RootErrors naive_double = root_errors(s, o, RootForm::naive, Precision::f64);
  EXPECT_EQ(naive_double.wrong_hit_miss, 0);
}

TEST(RootForms, StableRootsMatchLongDoubleWithinAFewUlpsWhereTheTextbookFormDoesNot) {
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> u(-1, 1);
  double worst_stable_f = 0, worst_naive_f = 0, worst_stable_d = 0;
  for (int i = 0; i < 4000; ++i) {
    // Far spheres (distance up to 1e5 times the radius): where cancellation bites.
    double radius = std::pow(10, 2 * u(rng));
    double distance = radius * std::pow(10, 1 + 2 * (u(rng) + 1));
    Vec3<double> centre{u(rng) * distance, u(rng) * distance, -distance};
    Vec3<double> target = centre + radius * 0.9 * glm::normalize(Vec3<double>{u(rng), u(rng), 1});
    Vec3<long double> o_l(0), c_l(centre), t_l(target);
    Vec3<long double> d_l = glm::normalize(t_l - o_l);
    auto ref = sphere_roots(o_l, d_l, c_l, static_cast<long double>(radius));
    if (!ref) continue;
    auto rel = [&](auto roots) {
      if (!roots) return 1.0;
      return static_cast<double>(std::fabs(roots->near - ref->near) / ref->near);
    };
    Vec3<float> d_f(d_l), c_f(c_l);
    Vec3<double> d_d(d_l);
    worst_stable_f = std::max(worst_stable_f, rel(sphere_roots(Vec3<float>(0), d_f, c_f, float(radius))));
    worst_naive_f = std::max(worst_naive_f, rel(sphere_roots_naive(Vec3<float>(0), d_f, c_f, float(radius))));
    worst_stable_d = std::max(worst_stable_d, rel(sphere_roots(Vec3<double>(0), d_d, centre, radius)));
  }
  EXPECT_LT(worst_stable_f, 1e-4);
  EXPECT_LT(worst_stable_d, 1e-12);
  EXPECT_GT(worst_naive_f, 1e-2) << "the textbook form should fail visibly on far spheres";
}

}  // namespace
}  // namespace rayfarm
