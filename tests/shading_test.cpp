// Classic shading (docs/rendering.md#shading) on tiny scenes, pixels worked out by hand from the
// formulas (in long double here, independently of the tracer), asserted to the byte.
#include <cmath>

#include "test_util.h"

namespace rayfarm {
namespace {

using test::byte_of;
using test::pixel;
using test::render;
using test::scene_from;

// One pixel looking straight down -z from (1, 1, 5) through (1, 1, 0).
const std::string kOnePixelCamera = R"(
camera c { pixeldim 1 1  worlddim 2 2  viewpoint 1 1 5 }
)";

TEST(Shading, AmbientIsDividedByTravelledDistance) {
  Scene s = scene_from(kOnePixelCamera + R"(
    material m { ambient 0.8 0.45 18 }
    sphere { material m center 1 1 -5 radius 1 })");
  Image img = render(s);
  // The ray travels from z = 5 to the sphere's front at z = -4: R = 9; 18/9 clamps to 1.
  EXPECT_EQ(pixel(img, 0, 0), (std::array<int, 3>{byte_of(0.8L / 9), byte_of(0.45L / 9), 255}));
}

TEST(Shading, LightStraightOnAddsEmissivityOverDistanceTimesDiffuse) {
  Scene s = scene_from(kOnePixelCamera + R"(
    material m { ambient 0 diffuse 0.45 0.3 0.75 }
    light { location 1 1 5 emissivity 9 4.5 9 }
    sphere { material m center 1 1 -5 radius 1 })");
  Image img = render(s);
  // N.L = 1, light distance r = 9.
  EXPECT_EQ(pixel(img, 0, 0),
            (std::array<int, 3>{byte_of(9.0L / 9 * 0.45L), byte_of(4.5L / 9 * 0.3L),
                                byte_of(9.0L / 9 * 0.75L)}));
}

TEST(Shading, PhongHighlightAtAnAngleFollowsTheFormula) {
  // Light off to the side: N = (0,0,1) at the hit point (1,1,-4), V = (0,0,1).
  Scene s = scene_from(kOnePixelCamera + R"(
    material m { ambient 0 diffuse 0.1 specular 0.6 shininess 8 }
    light { location 4 1 1 emissivity 6 }
    sphere { material m center 1 1 -5 radius 1 })");
  RenderOptions o;
  o.max_depth = 0;  // only the highlight, no reflection
  Image img = render(s, o);
  long double lx = 3, lz = 5, r = std::sqrt(lx * lx + lz * lz);
  long double nl = lz / r;                    // N.L
  long double rv = 2 * nl * 1 - lz / r;       // (2(N.L)N - L).V, V = N
  long double c = 6 / r * (0.1L * nl + 0.6L * std::pow(rv, 8.0L));
  EXPECT_EQ(pixel(img, 0, 0)[0], byte_of(c));
  EXPECT_EQ(pixel(img, 0, 0)[1], byte_of(c));
}

TEST(Shading, BlinnHighlightUsesTheHalfVector) {
  Scene s = scene_from(kOnePixelCamera + R"(
    material m { specular 0.8 shininess 4 }
    light { location 4 1 1 emissivity 6 }
    sphere { material m center 1 1 -5 radius 1 })");
  RenderOptions o;
  o.max_depth = 0;
  o.highlight = Highlight::blinn;
  Image img = render(s, o);
  long double lx = 3, lz = 5, r = std::sqrt(lx * lx + lz * lz);
  long double hx = lx / r, hz = lz / r + 1, hl = std::sqrt(hx * hx + hz * hz);
  long double c = 6 / r * (0.8L * std::pow(hz / hl, 4.0L));
  EXPECT_EQ(pixel(img, 0, 0)[0], byte_of(c));
}

TEST(Shading, OneReflectionAddsSpecularTimesTheReflectedColour) {
  // A mirror at z = -4 facing the eye; the reflected ray flies back past the eye to a wall at
  // z = 10 whose ambient 6.9 over the total path 9 + 14 = 23 gives 0.3.
  Scene s = scene_from(kOnePixelCamera + R"(
    material mirror { ambient 0.18 specular 0.5 }
    material wall { ambient 6.9 }
    plane { material mirror normal 0 0 1 point 0 0 -4 }
    plane { material wall normal 0 0 -1 point 0 0 10 })");
  Image img = render(s);
  long double local = 0.18L / 9;
  EXPECT_EQ(pixel(img, 0, 0)[0], byte_of(local + 0.5L * (6.9L / 23)));

  RenderOptions no_bounce;
  no_bounce.max_depth = 0;
  EXPECT_EQ(pixel(render(s, no_bounce), 0, 0)[0], byte_of(local));
}

TEST(Shading, ReflectionIsClampedAtEachLevel) {
  // The wall alone would be 4.6/23 * 10 = 2 (clamped to 1): the mirror adds 0.5 * 1.
  Scene s = scene_from(kOnePixelCamera + R"(
    material mirror { ambient 0.9 specular 0.5 }
    material wall { ambient 46 }
    plane { material mirror normal 0 0 1 point 0 0 -4 }
    plane { material wall normal 0 0 -1 point 0 0 10 })");
  EXPECT_EQ(pixel(render(s), 0, 0)[0], byte_of(0.9L / 9 + 0.5L * 1));
}

TEST(Shading, ShadowedPointGetsOnlyAmbient) {
  const std::string text = kOnePixelCamera + R"(
    material m { ambient 0.8 diffuse 0.5 }
    light { location 1 1 5 emissivity 9 }
    sphere { material m center 1 1 -5 radius 1 }
    sphere blocker { material m center 2.8 2.8 0.5 radius 0.1 }
    light { location 3 3 1 emissivity 9 })";
  // The second light sits just behind a small sphere, seen from the hit point (1, 1, -4).
  Scene s = scene_from(text);
  long double r2 = std::sqrt(4.0L + 4 + 25);
  long double lit_by_first = 0.8L / 9 + 9.0L / 9 * 0.5L;
  EXPECT_EQ(pixel(render(s), 0, 0)[0], byte_of(lit_by_first));

  RenderOptions no_shadows;
  no_shadows.shadows = false;
  EXPECT_EQ(pixel(render(s, no_shadows), 0, 0)[0],
            byte_of(lit_by_first + 9 / r2 * 0.5L * (5 / r2)));
}

TEST(Shading, MissIsBackgroundAndMaxDistCutsHits) {
  Scene s = scene_from(kOnePixelCamera + R"(
    material m { ambient 4.05 }
    sphere { material m center 1 1 -5 radius 1 })");
  RenderOptions o;
  o.background = {0.2, 0.4, 0.6};
  o.max_dist = 8.5;  // the hit is at 9
  EXPECT_EQ(pixel(render(s, o), 0, 0), (std::array<int, 3>{byte_of(0.2L), byte_of(0.4L),
                                                          byte_of(0.6L)}));
  o.max_dist = 9.5;
  EXPECT_EQ(pixel(render(s, o), 0, 0)[0], byte_of(4.05L / 9));
}

TEST(Shading, LightBehindTheSurfaceAddsNothing) {
  Scene s = scene_from(kOnePixelCamera + R"(
    material m { ambient 0.8 diffuse 1 }
    light { location 1 1 -20 emissivity 100 }
    sphere { material m center 1 1 -5 radius 1 })");
  RenderOptions no_shadows;
  no_shadows.shadows = false;
  Image img = render(s, no_shadows);
  EXPECT_EQ(pixel(img, 0, 0)[0], byte_of(0.8L / 9));
}

TEST(Shading, EyeInsideASphereSeesItsInside) {
  // From (1,1,5) inside a sphere of radius 10 at (1,1,5): the far side is 10 away.
  Scene s = scene_from(kOnePixelCamera + R"(
    material m { ambient 3.3 }
    sphere { material m center 1 1 5 radius 10 })");
  EXPECT_EQ(pixel(render(s), 0, 0)[0], byte_of(3.3L / 10));
}

TEST(Camera, TopImageRowIsTheTopOfTheWindow) {
  // 3x3 pixels over a 2x2 window: pixel (x=0, y=2) looks through world point (0, 2, 0). A
  // small sphere on that line lights only the first pixel of the file.
  Scene s = scene_from(R"(
    camera { pixeldim 3 3 worlddim 2 2 viewpoint 1 1 5 }
    material m { ambient 10 }
    sphere { material m center -1 3 -5 radius 0.3 })");
  Image img = render(s);
  for (int r = 0; r < 3; ++r)
    for (int x = 0; x < 3; ++x)
      EXPECT_EQ(pixel(img, x, r)[0] > 0, r == 0 && x == 0) << "x=" << x << " row=" << r;
}

TEST(Camera, SizeOverrideKeepsTheWorldWindow) {
  Scene s = scene_from(R"(
    camera { pixeldim 3 3 worlddim 2 2 viewpoint 1 1 5 }
    material m { ambient 10 }
    sphere { material m center -1 3 -5 radius 0.3 })");
  RenderOptions o;
  o.width = 5;
  o.height = 4;
  Image img = render(s, o);
  ASSERT_EQ(img.width, 5);
  ASSERT_EQ(img.height, 4);
  EXPECT_GT(pixel(img, 0, 0)[0], 0);
  EXPECT_EQ(pixel(img, 4, 3)[0], 0);
}

TEST(Camera, NamedCameraIsUsedAndUnknownNameIsAnError) {
  Scene s = scene_from(R"(
    camera first { pixeldim 2 2 worlddim 2 2 viewpoint 1 1 5 }
    camera second { pixeldim 4 3 worlddim 2 2 viewpoint 1 1 5 }
    material m { ambient 1 }
    sphere { material m center 1 1 -5 radius 1 })");
  RenderOptions o;
  o.camera = "second";
  EXPECT_EQ(render(s, o).width, 4);
  o.camera = "third";
  std::string error;
  Image img = render_image(s, o, 1, nullptr, {}, nullptr, &error);
  EXPECT_EQ(img.width, 0);
  EXPECT_NE(error.find("no camera named 'third'"), std::string::npos);
  EXPECT_NE(error.find("first, second"), std::string::npos);
  // Unnamed cameras are counted, not listed as empty names ("(cameras: b, )").
  Scene two = scene_from(R"(
    camera { pixeldim 2 2 worlddim 2 2 viewpoint 1 1 5 }
    camera b { pixeldim 2 2 worlddim 2 2 viewpoint 1 1 5 }
    camera { pixeldim 2 2 worlddim 2 2 viewpoint 1 1 5 }
    material m { ambient 1 }
    sphere { material m center 1 1 -5 radius 1 })");
  EXPECT_EQ(two.camera_names(), "b; 2 unnamed");
  render_image(two, o, 1, nullptr, {}, nullptr, &error);
  EXPECT_EQ(error, "no camera named 'third' (cameras: b; 2 unnamed)");
}

}  // namespace
}  // namespace rayfarm
