// The kinds the lecture profile gained beyond spheres and planes (fplane, tiled_plane,
// texplane, triangle, tri, revsurf, spotlight, projector, transparency) on tiny scenes
// whose bytes are worked out by hand from docs/rendering.md#shading and each kind's rule, in long
// double here, independently of the tracer. The lecture's colour at a hit R from the eye:
// ambient/R + Σ E/r (diffuse N·L), clamped, then floor(255c + 0.5).
#include <cmath>

#include "hand_computed.h"

namespace rayfarm {
namespace {

using namespace test;

// ---------------------------------------------------------------------------------------
// fplane

TEST(Fplane, IncludesItsNearEdges) {
  // From (1, 1, −5), 2.5 square: the middle column meets it at q.x = 0 exactly, the middle
  // row at q.y = 0; the right column and top row at q ≈ 2, inside.
  const Scene s = scene_from(kCamera + R"(
    material m { ambient 10 }
    fplane { material m normal 0 0 1 point 1 1 -5 xdir 1 0 0 dimensions 2.5 2.5 })");
  const Image img = render(s);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x)
      EXPECT_EQ(at(img, x, y, 0), x >= 1 && y >= 1 ? round_byte(10 / wall_distance(x, y)) : 0)
          << x << "," << y;
}

TEST(Fplane, IncludesItsFarEdgeAndNothingBeyond) {
  // From x = −0.5, 1.5 wide: the middle column meets it at q.x = 1.5 = w exactly.
  auto scene = [](const std::string& width) {
    return scene_from(kCamera + R"(
      material m { ambient 10 }
      fplane { material m normal 0 0 1 point -0.5 -2 -5 xdir 1 0 0 dimensions )" +
                      width + " 10 }");
  };
  const Image img = render(scene("1.5"));
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x)
      EXPECT_EQ(at(img, x, y, 0), x == 1 ? round_byte(10 / wall_distance(x, y)) : 0)
          << x << "," << y;
  const Image narrower = render(scene("1.4999"));
  for (int y = 0; y < 3; ++y) EXPECT_EQ(at(narrower, 1, y, 0), 0) << y;
}

TEST(Fplane, IsLitFromTheSideItIsSeenFrom) {
  // Its normal points away from the eye; two-sided, it is turned to face the ray, and the
  // light at the eye lights it: 4.5 · (10/d)/d with r = d.
  const Scene s = scene_from(kCamera + R"(
    material m { diffuse 4.5 0 0 }
    light { location 1 1 5 emissivity 1 }
    fplane { material m normal 0 0 -1 point -2 4 -5 xdir 1 0 0 dimensions 6 6 })");
  const Image img = render(s);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x) {
      const L d = wall_distance(x, y);
      EXPECT_EQ(at(img, x, y, 0), round_byte(4.5L * (10 / d) / d)) << x << "," << y;
    }
}

// ---------------------------------------------------------------------------------------
// tiled_plane

TEST(TiledPlane, OddSquaresUseTheMaterialEvenSquaresTheAltmaterial) {
  // docs/profiles.md §3's parity on the frame coordinates of the hit itself (2x − 1, 2y − 1): with
  // 2×2 tiles the square index is 9999 + x plus 9999 + y, odd (the material) when x + y is.
  // Both ambient and diffuse switch. Light at the eye: r = d, N·L = 10/d.
  const Scene s = scene_from(kCamera + R"(
    material m { ambient 5 0 0 diffuse 0 4.5 0 }
    material alt { ambient 0 0 5 diffuse 0 0 4.5 }
    light { location 1 1 5 emissivity 1 }
    tiled_plane { material m normal 0 0 1 point 2 0 -5 xdir 1 0 0 dimensions 2 2 altmaterial alt })");
  const Image img = render(s);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x) {
      const L d = wall_distance(x, y), diffuse = 4.5L * (10 / d) / d;
      const bool odd = (x + y) % 2 == 1;
      EXPECT_EQ(at(img, x, y, 0), odd ? round_byte(5 / d) : 0) << x << "," << y;
      EXPECT_EQ(at(img, x, y, 1), odd ? round_byte(diffuse) : 0) << x << "," << y;
      EXPECT_EQ(at(img, x, y, 2), odd ? 0 : round_byte(5 / d + diffuse)) << x << "," << y;
    }
}

TEST(TiledPlane, The2009FormAlternatesOnlyTheAmbientOnWorldXAndZ) {
  // Even squares are the foreground (the plane's own material), as in the cpsc102 profile.
  const Image img = render(scene_from(kFloor2009));
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x) {
      const FloorHit h = floor_hit(x, y);
      const bool fg = foreground_2009(h.px, h.pz);
      L cos, d;
      floor_light(h, cos, d);
      EXPECT_EQ(at(img, x, y, 0), fg ? round_byte(5 / h.path) : 0) << x << "," << y;
      EXPECT_EQ(at(img, x, y, 1), fg ? 0 : round_byte(5 / h.path)) << x << "," << y;
      EXPECT_EQ(at(img, x, y, 2), round_byte(4.5L * cos / d)) << x << "," << y;
    }
}

// ---------------------------------------------------------------------------------------
// texplane

// Over the wall from (−2.5, −2.5, −5), 6×6: pixel (x, y) meets it at q = (2x + 1.5,
// 2y + 1.5). Ambient and diffuse 4.3 under a light at the eye: 4.3/d + 4.3 · (10/d)/d,
// 0.86 at the centre, both times the texel.
std::string texplane_scene(int mode) {
  return kCamera + R"(
    texture t { filename t.ppm }
    material m { ambient 4.3 diffuse 4.3 }
    light { location 1 1 5 emissivity 1 }
    texplane { material m normal 0 0 1 point -2.5 -2.5 -5 xdir 1 0 0 dimensions 6 6 texname t mode )" +
         std::to_string(mode) + " }";
}
L texplane_colour(int x, int y) {
  const L d = wall_distance(x, y);
  return 4.3L / d + 4.3L * (10 / d) / d;
}

TEST(TexPlane, Mode0StretchesTheImageAndMultipliesByTexelOver255) {
  // tx = floor(q.x/6 · 3) = x, ty = y, from file row 2 − y: the pixel's own image row.
  const Image tex = texture3();
  const Image img = render(scene_from(texplane_scene(0), {{"t.ppm", tex}}));
  for (int r = 0; r < 3; ++r)
    for (int x = 0; x < 3; ++x)
      for (int c = 0; c < 3; ++c)
        EXPECT_EQ(pixel(img, x, r)[c],
                  round_byte(texplane_colour(x, 2 - r) * texel(tex, x, r, c) / 255))
            << x << "," << r << "," << c;
  // The white centre texel: 0.86 -> 219 (texel/256 would give 218).
  EXPECT_EQ(pixel(img, 1, 1)[0], 219);
}

TEST(TexPlane, Mode1RepeatsOneTexelPerPixelOfWorldSize) {
  // A pixel is 2/3 world units: tx = floor(q.x / (2/3)) mod 4 = 2, 5, 8 mod 4 = 2, 1, 0.
  const Image tex = texture4();
  const Image img = render(scene_from(texplane_scene(1), {{"t.ppm", tex}}));
  const int index[3] = {2, 1, 0};
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x)
      for (int c = 0; c < 3; ++c)
        EXPECT_EQ(at(img, x, y, c),
                  round_byte(texplane_colour(x, y) * texel(tex, index[x], 3 - index[y], c) / 255))
            << x << "," << y << "," << c;
}

// ---------------------------------------------------------------------------------------
// triangle and tri

// Lit pixels of a triangle (1, −3), (1, 5), (4, 1) on the wall: the middle column lies on
// its edge x = 1 (exactly: those rays have no x component), (2, 1) meets (3, 1) inside, and
// (2, 0) and (2, 2) meet (3, ∓1), 2/3 outside the slanted edges.
void expect_triangle_pixels(const Image& img) {
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x) {
      const bool hit = x == 1 || (x == 2 && y == 1);
      EXPECT_EQ(at(img, x, y, 0), hit ? round_byte(10 / wall_distance(x, y)) : 0) << x << "," << y;
    }
}

TEST(Triangle, InsideAndOnItsEdgesIsHitOutsideIsNot) {
  expect_triangle_pixels(render(scene_from(kCamera + R"(
    material m { ambient 10 }
    triangle { material m normal 0 0 1 point 0 0 -5 vertex1 1 -3 -5 vertex2 1 5 -5 vertex3 4 1 -5 })")));
}

TEST(Triangle, EdgeCountsWhicheverWayItsVerticesTurn) {
  // The same triangle counter-clockwise: the inside's edge signs are the other way round.
  expect_triangle_pixels(render(scene_from(kCamera + R"(
    material m { ambient 10 }
    triangle { material m normal 0 0 1 point 0 0 -5 vertex1 1 5 -5 vertex2 1 -3 -5 vertex3 4 1 -5 })")));
}

TEST(Triangle, VerticesAreProjectedAlongTheNormalIntoItsPlane) {
  // The same triangle with its vertices off the plane z = −5 in front and behind.
  expect_triangle_pixels(render(scene_from(kCamera + R"(
    material m { ambient 10 }
    triangle { material m normal 0 0 1 point 0 0 -5 vertex1 1 -3 -1 vertex2 1 5 -9 vertex3 4 1 -5 })")));
}

// Whether three points make a triangle does not depend on the scale they are written at
// (up to the ±1e150 of every position: past it a vertex is refused, ModelParser's tests).
TEST(Triangle, HasAnAreaAtAnyScale) {
  for (const char* scale : {"1e-100", "1e-10", "1", "1e100", "1e150"}) {
    SCOPED_TRACE(scale);
    const std::string s(scale);
    const std::string text = kCamera + "material m { ambient 1 }\n"
                             "tri t { material m v0 -" + s + " -" + s + " -5 v1 " + s + " -" + s +
                             " -5 v2 0 " + s + " -5 }\n"
                             "tri line { material m v0 -" + s + " -" + s + " -5 v1 0 0 -5 v2 " + s +
                             " " + s + " -5 }\n";
    LoadedScene loaded = load_scene(text);
    std::vector<std::string> degenerate;
    for (const Diagnostic& d : loaded.diags.items())
      if (d.code == "degenerate") degenerate.push_back(d.message.substr(0, 10));
    EXPECT_EQ(degenerate, std::vector<std::string>{"tri 'line'"});
  }
}

TEST(Tri, LiesInThePlaneThroughItsVertices) {
  // v0 v1 v2 span the plane z = −5 + (y − 1)/2, normal (v1 − v0) × (v2 − v1) ∝ (0, −1, 2).
  // Pixel (x, y) meets it s = 10/(5 + (y − 1)/2) times (x − 1, y − 1, −5) from the eye;
  // lit from the eye, N·L = |N·dir|.
  const Scene s = scene_from(kCamera + R"(
    material m { ambient 3 diffuse 3 }
    light { location 1 1 5 emissivity 1 }
    tri { material m v0 -10 -10 -10.5 v1 10 -10 -10.5 v2 1 20 4.5 })");
  const Image img = render(s);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x) {
      const L len = std::sqrt(L((x - 1) * (x - 1) + (y - 1) * (y - 1) + 25));
      const L t = 10 / (5 + (y - 1) / 2.0L) * len;
      const L n_dot_l = std::abs(-(y - 1) - 10.0L) / (std::sqrt(5.0L) * len);
      EXPECT_EQ(at(img, x, y, 0), round_byte(3 / t + 3 * n_dot_l / t)) << x << "," << y;
    }
  // At the centre: 0.3 + 0.3 · 2/√5 = 0.568 -> 145 (the untilted wall z = −5 would give 153).
  EXPECT_EQ(centre(img, 0), 145);
}

// ---------------------------------------------------------------------------------------
// revsurf

TEST(Revsurf, ConeIsHitWhereItsRadiusMeetsTheRayWithTheGradientNormal) {
  // r(y) = 4 − 2y/3 about the vertical axis through (1, −2, −15): the centre ray runs at
  // axial height 3 (r = 2) and meets it at (1, 1, −13), 18 from the eye. The normal is the
  // gradient of |radial|² − r², halved: radial (0, 0, 2) and axial −r r' = 4/3, so
  // N = (0, 2, 3)/√13. Red: ambient over 18; green: lit from the eye (N·L = 3/√13, r = 18);
  // blue: lit from straight above (N·L = 2/√13, r = 10).
  const Scene s = scene_from(kCamera + R"(
    material m { ambient 8.1 0 0 diffuse 0 9 9 }
    light { location 1 1 5 emissivity 0 1 0 }
    light { location 1 11 -13 emissivity 0 0 1 }
    revsurf { material m surfer 1 base 1 -2 -15 direction 0 1 0 height 6 })");
  const Image img = render(s);
  const L root13 = std::sqrt(13.0L);
  EXPECT_EQ(centre(img, 0), round_byte(8.1L / 18));
  EXPECT_EQ(centre(img, 1), round_byte(9 * (3 / root13) / 18));
  EXPECT_EQ(centre(img, 2), round_byte(9 * (2 / root13) / 10));
}

// A cone written taller than 6 ends at its apex in both profiles: r(y) = 4 − 2y/3 is 0 there,
// and a negative radius is no surface (not a second cone above). No course scene is taller
// than 6 (revsurfa: exactly 6), so the reference images cannot contradict it.
TEST(Revsurf, ConeEndsAtItsApex) {
  // Height 9, but r(y) = 4 − 2y/3 reaches 0 at y = 6: above it there would be no surface
  // (a negative radius is none). The centre ray runs at axial height 7.5, where |r| is 1,
  // and would go on to the wall z = −20, 25 away: 11/25 = 0.44 -> 112.
  const Scene s = scene_from(kCamera + R"(
    material m { ambient 0 9 0 }
    material wall { ambient 11 0 0 }
    revsurf { material m surfer 1 base 1 -6.5 -15 direction 0 1 0 height 9 }
    plane { material wall normal 0 0 1 point 0 0 -20 })");
  const Image img = render(s);
  EXPECT_EQ(centre(img, 0), round_byte(11.0L / 25));
  EXPECT_EQ(centre(img, 1), 0);
  RenderOptions course;
  course.profile = Profile::cpsc102;
  EXPECT_EQ(centre(render(s, course), 0), trunc_byte(11.0L / 25)) << "as the cpsc102 profile";
}

// ---------------------------------------------------------------------------------------
// spotlight and projector

TEST(Spotlight, LightsOnlyInsideItsCone) {
  // From the eye towards (1, 1, −5), half-angle 13°: the middle pixels are 11.3° off the
  // axis and lit as by a point light, the corners 15.8° off and dark.
  const Scene s = scene_from(kCamera + R"(
    material m { diffuse 0 4.5 0 }
    spotlight { location 1 1 5 emissivity 1 point 1 1 -5 theta 13 }
    plane { material m normal 0 0 1 point 0 0 -5 })");
  const Image img = render(s);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x) {
      const L d = wall_distance(x, y);
      const bool corner = x != 1 && y != 1;
      EXPECT_EQ(at(img, x, y, 1), corner ? 0 : round_byte(4.5L * (10 / d) / d)) << x << "," << y;
    }
}

TEST(Projector, FiltersItsLightByTheSlidesTexelOver255) {
  // The slide lies in z = 0 from (−0.5, −0.5), 2.4 square. From the light at the eye the
  // ray towards pixel (x, y)'s hit crosses it at (x, y, 0): q = (x + 0.5, y + 0.5), inside
  // for x, y <= 1, texel floor(1.25 q) = (x, y), file row 2 − y.
  const Image tex = texture3();
  const Scene s = scene_from(kCamera + R"(
    texture slide { filename slide.ppm }
    material m { diffuse 8.6 8.6 8.6 }
    projector { location 1 1 5 emissivity 1 point -0.5 -0.5 0 normal 0 0 1 xdir 1 0 0
                dimensions 2.4 2.4 texname slide mode 0 }
    plane { material m normal 0 0 1 point 0 0 -5 })",
                             {{"slide.ppm", tex}});
  const Image img = render(s);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x)
      for (int c = 0; c < 3; ++c) {
        const L d = wall_distance(x, y);
        const int expected =
            x <= 1 && y <= 1 ? round_byte(texel(tex, x, 2 - y, c) / 255.0L * 8.6L * (10 / d) / d)
                             : 0;
        EXPECT_EQ(at(img, x, y, c), expected) << x << "," << y << "," << c;
      }
}

// ---------------------------------------------------------------------------------------
// transparency

TEST(Transparency, MixesTheClampedLocalColourWithTheFilteredColourBehind) {
  // Glass 8 from the eye, wall 2 behind it: local 11/8 clamped to 1, behind 4.8/10, filter
  // 0.6 · (1, 0.5, 0.25)/1: c = 0.4 · 1 + (0.6, 0.3, 0.15) · 0.48.
  const Scene s = scene_from(kCamera + R"(
    material glass { ambient 11 diffuse 1 0.5 0.25 transparency 0.6 }
    material wall { ambient 4.8 }
    plane { material glass normal 0 0 1 point 0 0 -3 }
    plane { material wall normal 0 0 1 point 0 0 -5 })");
  const Image img = render(s);
  const L filter[3] = {0.6L, 0.3L, 0.15L};
  for (int c = 0; c < 3; ++c) EXPECT_EQ(centre(img, c), round_byte(0.4L + filter[c] * 0.48L)) << c;
}

TEST(Transparency, ShadowRayIsFilteredOncePerTranslucentObject) {
  // The light (7, 1, 3) is 10 from the centre hit along (0.6, 0, 0.8); the shadow ray runs
  // through the middle of a glass ball (in and out) whose filter is 0.5 · (1, 0.5, 0)/1.
  // 1/10 · 9 · 0.8 · filter once: (0.36, 0.18, 0); twice would be (0.18, 0.045, 0).
  const Scene s = scene_from(kCamera + R"(
    material glass { diffuse 1 0.5 0 transparency 0.5 }
    material wall { diffuse 9 9 9 }
    light { location 7 1 3 emissivity 1 }
    sphere { material glass center 4 1 -1 radius 1 }
    plane { material wall normal 0 0 1 point 0 0 -5 })");
  const Image img = render(s);
  EXPECT_EQ(centre(img, 0), round_byte(0.72L * 0.5L));
  EXPECT_EQ(centre(img, 1), round_byte(0.72L * 0.25L));
  EXPECT_EQ(centre(img, 2), 0);
}

TEST(Transparency, ShadowRayIsFilteredOncePerObjectPastEightObjects) {
  // Nine glass balls (filter 0.9 each) strung along the shadow ray of the previous test,
  // each crossed in and out: 0.72 · 0.9^9 = 0.279 -> 71 (one filtered twice: 64).
  std::string balls;
  for (int k = 1; k <= 9; ++k)
    balls += "sphere { material glass center " + std::to_string(1 + 0.6 * k) + " 1 " +
             std::to_string(-5 + 0.8 * k) + " radius 0.4 }\n";
  const Scene s = scene_from(kCamera + R"(
    material glass { diffuse 1 transparency 0.9 }
    material wall { diffuse 9 }
    light { location 7 1 3 emissivity 1 }
    plane { material wall normal 0 0 1 point 0 0 -5 })" +
                             balls);
  EXPECT_EQ(centre(render(s), 0), round_byte(0.72L * std::pow(0.9L, 9.0L)));
}

}  // namespace
}  // namespace rayfarm
