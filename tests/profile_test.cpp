// The cpsc102 profile (docs/profiles.md) on tiny scenes whose bytes are worked out by hand from the
// course's rules, in long double here, independently of the reference tracer. Where a rule
// differs from the lecture profile, the lecture's byte is asserted beside it.
#include <cmath>
#include <cstdlib>

#include "hand_computed.h"
#include "rayfarm/lint.h"
#include "render/cpsc102/glibc_random.h"

namespace rayfarm {
namespace {

using namespace test;

RenderOptions course(RenderOptions o = {}) {
  o.profile = Profile::cpsc102;
  return o;
}

// ---------------------------------------------------------------------------------------
// §1 Camera and bytes

TEST(Cpsc102, BytesTruncateWhereTheLectureRounds) {
  const Scene s = scene_from(kCamera + R"(
    material m { ambient 5 }
    plane { material m normal 0 0 1 point 0 0 -5 })");
  // The centre ray meets the wall 10 away: 5/10 = 0.5, exactly 127.5 on the byte scale.
  EXPECT_EQ(centre(render(s, course()), 0), 127);
  RenderOptions nearest = course();
  nearest.rounding = Rounding::nearest;
  EXPECT_EQ(centre(render(s, nearest), 0), 128);
  EXPECT_EQ(centre(render(s), 0), 128) << "the lecture rounds";
  RenderOptions truncate;
  truncate.rounding = Rounding::truncate;
  EXPECT_EQ(centre(render(s, truncate), 0), 127);
}

TEST(Cpsc102, PixelYZeroIsTheBottomRowWithNoHalfPixelOffset) {
  // Small spheres on the lines from the eye through the screen points (0, 0, 0) and
  // (2, 2, 0). With a half-pixel offset pixel (0, 0) would look through (1/3, 1/3, 0) and
  // pass 0.94 from the first sphere's centre, outside its radius 0.3.
  const Scene s = scene_from(kCamera + R"(
    material a { ambient 10 0 0 }
    material b { ambient 0 10 0 }
    sphere { material a center -1 -1 -5 radius 0.3 }
    sphere { material b center 3 3 -5 radius 0.3 })");
  const Image img = render(s, course());
  // Each ray passes through its sphere's centre, 2·sqrt(27) from the eye: t = 2√27 − 0.3.
  const int lit = trunc_byte(10 / (2 * std::sqrt(27.0L) - 0.3L));
  ASSERT_EQ(lit, 252);
  EXPECT_EQ(pixel(img, 0, 2), (std::array<int, 3>{lit, 0, 0})) << "y = 0: the last file row";
  EXPECT_EQ(pixel(img, 2, 0), (std::array<int, 3>{0, lit, 0})) << "y = 2: the first file row";
  for (int r = 0; r < 3; ++r)
    for (int x = 0; x < 3; ++x) {
      if ((x == 0 && r == 2) || (x == 2 && r == 0)) continue;
      EXPECT_EQ(pixel(img, x, r), (std::array<int, 3>{0, 0, 0})) << x << "," << r;
    }
}

// ---------------------------------------------------------------------------------------
// §2 The trace: the local colour

// One light at (4, 1, −1), seen from the centre hit (1, 1, −5) at L = (0.6, 0, 0.8), d = 5,
// cos = 0.8; the eye is along V = (0, 0, 1), so H = unit(0.6, 0, 1.8) and N·H = 1.8/√3.6,
// (N·H)^4 = 0.81. Red is ambient only, green diffuse only, blue the glint only. The path to
// the wall is 10 long. (The mirror ray goes up to nothing: black.)
const std::string kLitWall = kCamera + R"(
  material m { ambient 4.3 0 0  diffuse 0 5 0  specular 0 0 2  shininess 4 }
  light { location 4 1 -1 emissivity 1 }
  plane { material m normal 0 0 1 point 0 0 -5 })";

TEST(Cpsc102, AmbientIsDividedByThePathLength) {
  // 4.3 / 10 = 0.43 -> 109.65.
  EXPECT_EQ(centre(render(scene_from(kLitWall), course()), 0), trunc_byte(4.3L / 10));
}

TEST(Cpsc102, DiffuseIsCosineOverLightDistanceThenDividedByThePathLength) {
  // 5 · 0.8 / 5 / 10 = 0.08 -> 20 (1/d² would give 4; without the path length, 204).
  const int g = trunc_byte(5 * 0.8L / 5 / 10);
  ASSERT_EQ(g, 20);
  EXPECT_EQ(centre(render(scene_from(kLitWall), course()), 1), g);
}

TEST(Cpsc102, GlintIsNDotHToTheShininessWithoutCosineOrOneOverDistance) {
  // 1 · 2 · 0.81 / 10 = 0.162 -> 41 (with cos: 33; with 1/d: 8; not divided by the path: 255).
  const L n_dot_h = 1.8L / std::sqrt(3.6L);
  const int b = trunc_byte(2 * std::pow(n_dot_h, 4.0L) / 10);
  ASSERT_EQ(b, 41);
  EXPECT_EQ(centre(render(scene_from(kLitWall), course()), 2), b);
}

// A light at (8, 1, 19), 25 from the centre hit along L = (0.28, 0, 0.96); a material with
// only a specular (blue) weight.
std::string glint_scene(const std::string& shininess) {
  return kCamera + "material m { specular 0 0 1 " + shininess + " }\n" + R"(
    light { location 8 1 19 emissivity 25 }
    plane { material m normal 0 0 1 point 0 0 -5 })";
}

TEST(Cpsc102, NoGlintWhenShininessIsUnsetOrZero) {
  EXPECT_EQ(centre(render(scene_from(glint_scene("")), course()), 2), 0);
  EXPECT_EQ(centre(render(scene_from(glint_scene("shininess 0")), course()), 2), 0);
  // The same light does glint with a shininess: H = unit(0.28, 0, 1.96), N·H = √0.98, and
  // 25 · 0.98^200 / 10 = 0.044 -> 11.
  const int b = trunc_byte(25 * std::pow(0.98L, 200.0L) / 10);
  ASSERT_EQ(b, 11);
  EXPECT_EQ(centre(render(scene_from(glint_scene("shininess 400")), course()), 2), b);
}

TEST(LectureProfile, GlintDefaultsToShininess32) {
  // Phong: Rl = 2(N·L)N − L = (−0.28, 0, 0.96), Rl·V = 0.96; E/r = 25/25.
  const int b = round_byte(std::pow(0.96L, 32.0L));
  ASSERT_EQ(b, 69);  // 0.96^31 would give 72, 0.96^33 66
  EXPECT_EQ(centre(render(scene_from(glint_scene(""))), 2), b);
}

// ---------------------------------------------------------------------------------------
// §2 The trace: reflection and MAX_DIST

// A mirror tilted 45° meets the centre ray at (1, 1, mirror_z) and sends it along −x to a
// wall at x = wall_x. With mirror_z = −7 and wall_x = −3 the mirror is 12 away and the
// wall 4 further: 16 in all.
std::string mirror_scene(const std::string& mirror, const std::string& wall, int mirror_z,
                         int wall_x) {
  return kCamera + "material mirror { " + mirror + " }\nmaterial wall { " + wall + " }\n" +
         "plane { material mirror normal -1 0 1 point 1 1 " + std::to_string(mirror_z) + " }\n" +
         "plane { material wall normal 1 0 0 point " + std::to_string(wall_x) + " 0 0 }\n";
}

TEST(Cpsc102, ReflectionAddsSpecularTimesTheReflectedColourUnscaled) {
  const Scene s = scene_from(mirror_scene("ambient 1.2 specular 0.5", "ambient 4", -7, -3));
  // 1.2/12 + 0.5 · 4/16 = 0.225 -> 57 (the local colour is not scaled by 1 − specular).
  EXPECT_EQ(centre(render(s, course()), 0), trunc_byte(1.2L / 12 + 0.5L * 4 / 16));
}

TEST(Cpsc102, ClampsOnlyOnceAtThePixel) {
  const Scene s = scene_from(mirror_scene("ambient 1.2 specular 0.25", "ambient 30", -7, -3));
  // The wall's own colour is 30/16 = 1.875: 0.1 + 0.25 · 1.875 = 0.56875 -> 145. The lecture
  // clamps the wall's level first: 0.1 + 0.25 · 1 = 0.35 -> 89.
  EXPECT_EQ(centre(render(s, course()), 0), trunc_byte(0.1L + 0.25L * 30 / 16));
  EXPECT_EQ(centre(render(s), 0), round_byte(0.1L + 0.25L));
}

TEST(Cpsc102, MaxDistIsTestedOnTheDistanceTravelledBeforeTheHit) {
  // The reflected ray starts 12 from the eye (<= 20) and meets the wall 13 further on: the
  // wall is shaded although the whole path is 25. 4/25 = 0.16 -> 40.
  const Scene s = scene_from(mirror_scene("specular 1", "ambient 4", -7, -12));
  EXPECT_EQ(centre(render(s, course()), 0), trunc_byte(4.0L / 25));
  // The lecture's max_dist cuts the hit itself: 25 > 20.
  RenderOptions lecture;
  lecture.max_dist = 20;
  EXPECT_EQ(centre(render(s, lecture), 0), 0);
}

TEST(Cpsc102, PathsLongerThanTwentyAreBlack) {
  // The mirror is 21 away: its reflected ray is not traced at all.
  const Scene s = scene_from(mirror_scene("specular 1", "ambient 4", -16, -3));
  EXPECT_EQ(centre(render(s, course()), 0), 0);
}

TEST(Cpsc102, MaxDistOptionReplacesTwenty) {
  RenderOptions longer = course();
  longer.max_dist = 30;
  // Mirror at 21, wall 4 further: 4/25 -> 40.
  EXPECT_EQ(centre(render(scene_from(mirror_scene("specular 1", "ambient 4", -16, -3)), longer), 0),
            trunc_byte(4.0L / 25));
  RenderOptions shorter = course();
  shorter.max_dist = 11;
  // Mirror at 12 > 11: no reflection.
  EXPECT_EQ(centre(render(scene_from(mirror_scene("specular 1", "ambient 4", -7, -3)), shorter), 0),
            0);
}

TEST(Cpsc102, GlintOfAReflectedRayLooksFromTheMirrorsStaleHitPoint) {
  // docs/profiles.md §8. The centre ray meets a small tilted mirror (an fplane) at (1, 1, −7) and goes
  // on along −x to a shiny wall x = −3, 16 from the eye. The light (0, 1, −9) is seen from
  // there along L = (3, 0, −2)/√13. Its shadow ray crosses the mirror's plane at
  // (−0.6, 1, −8.6), outside its window: no shadow, but the mirror's hit test stored that
  // point, and the glint's V now points from the wall to it: V = L, H = L, N·H = 3/√13.
  // 10 · (3/√13)^10 / 16 = 0.0995 -> 25 (from the true origin (1, 1, −7): N·H = 0.957,
  // 0.403 -> 102).
  const Scene s = scene_from(kCamera + R"(
    material mirror { specular 1 }
    material wall { specular 1 shininess 10 }
    light { location 0 1 -9 emissivity 10 }
    fplane { material mirror normal -1 0 1 point 1.3535533905932737 0.5 -6.6464466094067263
             xdir 0 1 0 dimensions 1 1 }
    plane { material wall normal 1 0 0 point -3 0 0 })");
  EXPECT_EQ(centre(render(s, course()), 0), trunc_byte(10 * std::pow(9.0L / 13, 5.0L) / 16));
}

// ---------------------------------------------------------------------------------------
// §3 Surfaces

TEST(Cpsc102, PlaneHitsInFrontOfTheScreenAreIgnored) {
  auto scene = [](const std::string& front_z) {
    return scene_from(kCamera + R"(
      material front { ambient 0 9 0 }
      material wall { ambient 4.3 0 0 }
      plane { material front normal 0 0 1 point 0 0 )" +
                      front_z + R"( }
      plane { material wall normal 0 0 1 point 0 0 -5 })");
  };
  // A plane at z = 3, between the eye and the screen: the centre ray goes through it.
  const Scene ahead = scene("3");
  EXPECT_EQ(centre(render(ahead, course()), 0), trunc_byte(4.3L / 10));
  EXPECT_EQ(centre(render(ahead, course()), 1), 0);
  EXPECT_EQ(centre(render(ahead), 1), 255) << "the lecture sees it: 9/2, clamped";
  // At z = 0.005 (not beyond 0.01) it counts: 9/4.995, clamped.
  EXPECT_EQ(centre(render(scene("0.005"), course()), 1), 255);
}

TEST(Cpsc102, ShadowRaysIgnorePlaneHitsInFrontOfTheScreen) {
  // The light at (1, 11, 5) is 10√2 from the centre hit along (0, 1, 1)/√2, cos = 1/√2.
  // A ceiling y = 8 crosses that shadow ray at z = 2 (ignored); y = 5 at z = −1 (it blocks).
  auto scene = [](const std::string& ceiling_y) {
    return scene_from(kCamera + R"(
      material wall { diffuse 0 90 0 }
      material ceiling { ambient 0 }
      light { location 1 11 5 emissivity 1 }
      plane { material wall normal 0 0 1 point 0 0 -5 }
      plane { material ceiling normal 0 1 0 point 0 )" +
                      ceiling_y + " 0 }");
  };
  const L d = 10 * std::sqrt(2.0L);
  // 90 · (1/√2) / (10√2) / 10 = 0.45 -> 114.
  EXPECT_EQ(centre(render(scene("8"), course()), 1), trunc_byte(90 / std::sqrt(2.0L) / d / 10));
  EXPECT_EQ(centre(render(scene("5"), course()), 1), 0);
  EXPECT_EQ(centre(render(scene("8")), 1), 0) << "the lecture's ceiling blocks";
}

TEST(Cpsc102, ReflectedRaysIgnorePlaneHitsInFrontOfTheScreen) {
  // A mirror facing the eye sends the centre ray back up to a wall behind the eye, z = 8.
  const Scene s = scene_from(kCamera + R"(
    material mirror { specular 1 }
    material wall { ambient 11.27 }
    plane { material mirror normal 0 0 1 point 0 0 -5 }
    plane { material wall normal 0 0 -1 point 0 0 8 })");
  EXPECT_EQ(centre(render(s, course()), 0), 0);
  // The lecture sees the wall after 10 + 13: 11.27/23 = 0.49 -> 125.
  EXPECT_EQ(centre(render(s), 0), round_byte(11.27L / 23));
}

TEST(Cpsc102, RayFromInsideASphereSeesNothingOfIt) {
  const Scene s = scene_from(kCamera + R"(
    material shell { ambient 3.3 }
    material wall { ambient 11 }
    sphere { material shell center 1 1 5 radius 10 }
    plane { material wall normal 0 0 1 point 0 0 -20 })");
  // Only the near root counts, and it is behind the eye: the ray goes on to the wall, 25
  // away: 11/25 = 0.44 -> 112. The lecture sees the sphere's inside 10 away: 0.33 -> 84.
  EXPECT_EQ(centre(render(s, course()), 0), trunc_byte(11.0L / 25));
  EXPECT_EQ(centre(render(s), 0), round_byte(3.3L / 10));
}

TEST(Cpsc102, NormalIsNeverTurnedTowardsTheViewer) {
  // An fplane whose normal points away from the eye, lit from the eye's side: cos < 0, no
  // light (the lecture turns the normal and lights it: see entities_test).
  const Scene s = scene_from(kCamera + R"(
    material m { ambient 0 4.3 0 diffuse 45 0 0 }
    light { location 1 1 5 emissivity 1 }
    fplane { material m normal 0 0 -1 point -2 4 -5 xdir 1 0 0 dimensions 6 6 })");
  const Image img = render(s, course());
  EXPECT_EQ(centre(img, 1), trunc_byte(4.3L / 10)) << "the fplane is hit";
  EXPECT_EQ(centre(img, 0), 0);
}

TEST(Cpsc102, FplaneIncludesItsNearEdges) {
  // The window starts at (1, 1, −5): the middle column meets it at q.x = 0 exactly, the
  // middle row at q.y = 0; the right column and top row well inside (q ≈ 2 of 2.5).
  const Scene s = scene_from(kCamera + R"(
    material m { ambient 10 }
    fplane { material m normal 0 0 1 point 1 1 -5 xdir 1 0 0 dimensions 2.5 2.5 })");
  const Image img = render(s, course());
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x)
      EXPECT_EQ(at(img, x, y, 0), x >= 1 && y >= 1 ? trunc_byte(10 / wall_distance(x, y)) : 0)
          << x << "," << y;
}

TEST(Cpsc102, FplaneIncludesItsFarEdge) {
  // From x = −0.5, 1.5 wide: the middle column (x = 1) meets it at q.x = 1.5 = w exactly.
  auto scene = [](const std::string& width) {
    return scene_from(kCamera + R"(
      material m { ambient 10 }
      fplane { material m normal 0 0 1 point -0.5 -2 -5 xdir 1 0 0 dimensions )" +
                      width + " 10 }");
  };
  const Image img = render(scene("1.5"), course());
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x)
      EXPECT_EQ(at(img, x, y, 0), x == 1 ? trunc_byte(10 / wall_distance(x, y)) : 0)
          << x << "," << y;
  const Image narrower = render(scene("1.4999"), course());
  for (int y = 0; y < 3; ++y) EXPECT_EQ(at(narrower, 1, y, 0), 0) << y;
}

TEST(Cpsc102, TriangleIsHitInsideAndOnItsEdgesInEitherWinding) {
  // docs/profiles.md §11's chosen rule. The triangle (1, −3), (1, 5), (4, 1) on the wall: the middle
  // column lies on its edge x = 1 exactly, (2, 1) meets (3, 1) inside, (2, 0) and (2, 2)
  // meet (3, ∓1), 2/3 outside the slanted edges. Both windings: the inside's edge signs
  // are one way or the other.
  for (const char* vertices : {"vertex1 1 -3 -5 vertex2 1 5 -5 vertex3 4 1 -5",
                               "vertex1 1 5 -5 vertex2 1 -3 -5 vertex3 4 1 -5"}) {
    const Image img = render(scene_from(kCamera + R"(
      material m { ambient 10 }
      triangle { material m normal 0 0 1 point 0 0 -5 )" +
                                        std::string(vertices) + " }"),
                             course());
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 3; ++x) {
        const bool hit = x == 1 || (x == 2 && y == 1);
        EXPECT_EQ(at(img, x, y, 0), hit ? trunc_byte(10 / wall_distance(x, y)) : 0)
            << vertices << ": " << x << "," << y;
      }
  }
}

TEST(Cpsc102, TiledPlaneOddSquaresUseTheMaterialEvenSquaresTheAltmaterial) {
  // Rot·P (not P − point) for the hit (2x − 1, 2y − 1, −5): with 2×2 tiles
  // ix = (int)((2x − 1)/2 + 10000) = 9999 + x, iy = 9999 + y, so x + y odd is `material`.
  // (With P − point = P − (2, 0, −5) ix would be 9998 + x: the parity flips.) The light is
  // at the eye, so d = path length = wall_distance and cos = 10/d.
  const Scene s = scene_from(kCamera + R"(
    material m { ambient 5 0 0 diffuse 0 45 0 }
    material alt { ambient 0 0 5 diffuse 0 0 45 }
    light { location 1 1 5 emissivity 1 }
    tiled_plane { material m normal 0 0 1 point 2 0 -5 xdir 1 0 0 dimensions 2 2 altmaterial alt })");
  const Image img = render(s, course());
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x) {
      const L d = wall_distance(x, y), diffuse = 45 * (10 / d) / d;
      const bool odd = (x + y) % 2 == 1;
      const std::array<int, 3> expected =
          odd ? std::array<int, 3>{trunc_byte(5 / d), trunc_byte(diffuse / d), 0}
              : std::array<int, 3>{0, 0, trunc_byte((5 + diffuse) / d)};
      EXPECT_EQ(at(img, x, y, 0), expected[0]) << x << "," << y;
      EXPECT_EQ(at(img, x, y, 1), expected[1]) << x << "," << y;
      EXPECT_EQ(at(img, x, y, 2), expected[2]) << x << "," << y;
    }
}

TEST(Cpsc102, TiledPlane2009FormAlternatesOnlyTheAmbientOnWorldXAndZ) {
  const Image img = render(scene_from(kFloor2009), course());
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x) {
      const FloorHit h = floor_hit(x, y);
      const bool fg = foreground_2009(h.px, h.pz);
      EXPECT_EQ(fg, y == 2 || (x + y) % 2 == 1) << "the pattern the comment promises";
      L cos, d;
      floor_light(h, cos, d);
      EXPECT_EQ(at(img, x, y, 0), fg ? trunc_byte(5 / h.path) : 0) << x << "," << y;
      EXPECT_EQ(at(img, x, y, 1), fg ? 0 : trunc_byte(5 / h.path)) << x << "," << y;
      // The diffuse is always the plane's own material's.
      EXPECT_EQ(at(img, x, y, 2), trunc_byte(4.5L * cos / d / h.path)) << x << "," << y;
    }
}

// A texplane over the wall from (−2.5, −2.5, −5), 6×6: pixel (x, y) meets it at
// q = (2x + 1.5, 2y + 1.5), well inside texels. Ambient 4.5 and diffuse 45 under a light at
// the eye: (4.5 + 45 · cos/d) / d with d = path = light distance, cos = 10/d.
std::string texplane_scene(int mode) {
  return kCamera + R"(
    texture t { filename t.ppm }
    material m { ambient 4.5 diffuse 45 }
    light { location 1 1 5 emissivity 1 }
    texplane { material m normal 0 0 1 point -2.5 -2.5 -5 xdir 1 0 0 dimensions 6 6 texname t mode )" +
         std::to_string(mode) + " }";
}
L texplane_colour(int x, int y) {
  const L d = wall_distance(x, y);
  return (4.5L + 45 * (10 / d) / d) / d;
}

TEST(Cpsc102, TexplaneMode0StretchesTheImageAndMultipliesByTexelOver256) {
  // tx = (int)(q.x/6 · 3) = x, ty = y, read from file row 3 − 1 − y: the image row of the
  // pixel itself.
  const Image tex = texture3();
  const Image img = render(scene_from(texplane_scene(0), {{"t.ppm", tex}}), course());
  for (int r = 0; r < 3; ++r)
    for (int x = 0; x < 3; ++x)
      for (int c = 0; c < 3; ++c)
        EXPECT_EQ(pixel(img, x, r)[c],
                  trunc_byte(texplane_colour(x, 2 - r) * texel(tex, x, r, c) / 256))
            << x << "," << r << "," << c;
  // At the centre (colour 0.9, texel 255) /255 would give 229, /256 gives 228.
  EXPECT_EQ(pixel(img, 1, 1)[0], 228);
}

TEST(Cpsc102, TexplaneMode1RepeatsOneTexelPerPixelOfWorldSize) {
  // A pixel is 2/3 world units: tx = (int)(q.x / (2/3)) mod 4 = 2, 5, 8 mod 4 = 2, 1, 0.
  const Image tex = texture4();
  const Image img = render(scene_from(texplane_scene(1), {{"t.ppm", tex}}), course());
  const int index[3] = {2, 1, 0};
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x)
      for (int c = 0; c < 3; ++c)
        EXPECT_EQ(at(img, x, y, c),
                  trunc_byte(texplane_colour(x, y) * texel(tex, index[x], 3 - index[y], c) / 256))
            << x << "," << y << "," << c;
}

// ---------------------------------------------------------------------------------------
// Lights

TEST(Cpsc102, SpotlightLightsOnlyInsideItsConeWithAHardEdge) {
  // From the eye towards (1, 1, −5), half-angle 13°: the middle pixels are 11.3° off the
  // axis and lit in full, the corners 15.8° off and dark. Light at the eye: cos = 10/d.
  const Scene s = scene_from(kCamera + R"(
    material m { diffuse 0 45 0 }
    spotlight { location 1 1 5 emissivity 1 point 1 1 -5 theta 13 }
    plane { material m normal 0 0 1 point 0 0 -5 })");
  const Image img = render(s, course());
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x) {
      const L d = wall_distance(x, y);
      const bool corner = x != 1 && y != 1;
      EXPECT_EQ(at(img, x, y, 1), corner ? 0 : trunc_byte(45 * (10 / d) / d / d)) << x << "," << y;
    }
}

TEST(Cpsc102, ProjectorFiltersItsLightByTheSlidesTexelOver256) {
  // The slide lies in z = 0 from (−0.5, −0.5), 2.4 square. From the light at the eye the
  // ray towards pixel (x, y)'s hit crosses it at (x, y, 0): q = (x + 0.5, y + 0.5), inside
  // for x, y <= 1, texel (int)(1.25 q) = (x, y), file row 2 − y.
  const Image tex = texture3();
  const Scene s = scene_from(kCamera + R"(
    texture slide { filename slide.ppm }
    material m { diffuse 90 90 90 }
    projector { location 1 1 5 emissivity 1 point -0.5 -0.5 0 normal 0 0 1 xdir 1 0 0
                dimensions 2.4 2.4 texname slide mode 0 }
    plane { material m normal 0 0 1 point 0 0 -5 })",
                             {{"slide.ppm", tex}});
  const Image img = render(s, course());
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x)
      for (int c = 0; c < 3; ++c) {
        const L d = wall_distance(x, y);
        const int expected =
            x <= 1 && y <= 1
                ? trunc_byte(90 * (texel(tex, x, 2 - y, c) / 256.0L) * (10 / d) / d / d)
                : 0;
        EXPECT_EQ(at(img, x, y, c), expected) << x << "," << y << "," << c;
      }
}

// ---------------------------------------------------------------------------------------
// §6 Transparency

TEST(Cpsc102, TranslucentColourMixesTheUnclampedLocalColourWithTheFilteredOneBehind) {
  // Glass 8 from the eye, wall 2 behind it. Local 11/8 = 1.375 (not clamped); behind 4.8/10;
  // filter 0.6 · (1, 0.5, 0.25) / 1: c = 0.4 · 1.375 + (0.6, 0.3, 0.15) · 0.48.
  const Scene s = scene_from(kCamera + R"(
    material glass { ambient 11 diffuse 1 0.5 0.25 transparency 0.6 }
    material wall { ambient 4.8 }
    plane { material glass normal 0 0 1 point 0 0 -3 }
    plane { material wall normal 0 0 1 point 0 0 -5 })");
  const Image img = render(s, course());
  const L filter[3] = {0.6L, 0.3L, 0.15L};
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(centre(img, c), trunc_byte(0.4L * 1.375L + filter[c] * 0.48L)) << c;
    // The lecture clamps the local colour first: 0.4 · 1 + ...
    EXPECT_EQ(centre(render(s), c), round_byte(0.4L + filter[c] * 0.48L)) << c;
  }
}

TEST(Cpsc102, ShadowRayThroughATranslucentObjectIsFilteredByIt) {
  // The light at the eye lights the wall through the glass: the wall's diffuse term is
  // 90 · filter · 1/10, over its path 10; the glass itself is lit straight on from 8 away.
  const Scene s = scene_from(kCamera + R"(
    material glass { diffuse 1 0.5 0.25 transparency 0.6 }
    material wall { diffuse 90 90 90 }
    light { location 1 1 5 emissivity 1 }
    plane { material glass normal 0 0 1 point 0 0 -3 }
    plane { material wall normal 0 0 1 point 0 0 -5 })");
  const Image img = render(s, course());
  const L diffuse[3] = {1, 0.5L, 0.25L};
  for (int c = 0; c < 3; ++c) {
    const L filter = 0.6L * diffuse[c];
    const L glass = diffuse[c] / 8 / 8, wall = 90 * filter / 10 / 10;
    EXPECT_EQ(centre(img, c), trunc_byte(0.4L * glass + filter * wall)) << c;
  }
}

// ---------------------------------------------------------------------------------------
// §10 revsurf

TEST(Cpsc102, ConeNormalHasItsAxialPartDoubled) {
  // The cone r(y) = 4 − 2y/3 about the vertical axis through (1, −2, −15): the centre ray
  // runs at axial height 3 (r = 2) and meets it at (1, 1, −13), 18 from the eye. Radial part
  // (0, 0, 2), axial part doubled: −2 · r · r' = 8/3, so N = (0, 0.8, 0.6). Green is lit from
  // the eye (cos 0.6, d 18), blue from straight above (cos 0.8, d 10).
  const Scene s = scene_from(kCamera + R"(
    material m { ambient 8.1 0 0 diffuse 0 81 81 }
    light { location 1 1 5 emissivity 0 1 0 }
    light { location 1 11 -13 emissivity 0 0 1 }
    revsurf { material m surfer 1 base 1 -2 -15 direction 0 1 0 height 6 })");
  const Image img = render(s, course());
  EXPECT_EQ(centre(img, 0), trunc_byte(8.1L / 18));
  EXPECT_EQ(centre(img, 1), trunc_byte(81 * 0.6L / 18 / 18));  // the true normal: 53
  EXPECT_EQ(centre(img, 2), trunc_byte(81 * 0.8L / 10 / 18));  // the true normal: 63
}

// A triangle whose plane the course's program cannot compute (the square of its edges' cross
// product overflows, and the unit normal comes out 0) is not drawn in this profile, as the
// program drew none: the lint says so at the triangle. The lecture profile draws it.
TEST(Cpsc102, ATriangleTooLargeForTheProgramsArithmeticIsNotDrawnAndSaidSo) {
  auto scene = [](const std::string& far) {
    return scene_from(kCamera + "material m { ambient 1 }\ntriangle t { material m vertex1 -10 "
                      "-10 -1 vertex2 " + far + " -10 -1 vertex3 -10 " + far + " -1 }\n");
  };
  auto lints = [](const Scene& s, const RenderOptions& o) {
    Diagnostics d;
    lint_scene(s, o, d);
    std::vector<Diagnostic> lost;
    for (const Diagnostic& x : d.items())
      if (x.code == "course-triangle-lost") lost.push_back(x);
    return lost;
  };
  const Scene near = scene("1e76"), far = scene("1e78");
  EXPECT_GT(centre(render(near, course()), 0), 0);
  EXPECT_EQ(centre(render(far, course()), 0), 0);
  EXPECT_GT(centre(render(far), 0), 0);
  EXPECT_TRUE(lints(near, course()).empty());
  EXPECT_TRUE(lints(far, {}).empty());
  const std::vector<Diagnostic> lost = lints(far, course());
  ASSERT_EQ(lost.size(), 1u);
  EXPECT_EQ(lost[0].where.line, 3);
  EXPECT_EQ(lost[0].message.rfind("triangle 't': the course's program cannot find its plane", 0),
            0u);
  // Too small, and tilted, so that no component of the cross product is 0 but their squares
  // are: the unit normal is infinite, and the program draws nothing either.
  const Scene tiny = scene_from(kCamera + "material m { ambient 1 }\ntri t { material m v0 0 0 0 "
                                          "v1 1e-100 3e-101 2e-101 v2 2e-101 1e-100 5e-101 }\n");
  EXPECT_EQ(lints(tiny, course()).size(), 1u);
  EXPECT_TRUE(lints(tiny, {}).empty());
}

// ---------------------------------------------------------------------------------------
// §11 Anti-aliasing

TEST(GlibcRandom, FirstValuesAreGlibcsSequenceForSeedOne) {
  // glibc's random() never seeded: 1804289383, 846930886, 1681692777, ...
  cpsc102::GlibcRandom r;
  for (std::uint32_t v : {1804289383u, 846930886u, 1681692777u, 1714636915u, 1957747793u,
                          424238335u, 719885386u, 1649760492u, 596516649u, 1189641421u})
    EXPECT_EQ(r.next(), v);
}

#if defined(__GLIBC__)
TEST(GlibcRandom, MatchesThisCLibrarysRandomOverAMillionValues) {
  srandom(1);
  cpsc102::GlibcRandom r;
  for (int i = 0; i < 1000000; ++i) ASSERT_EQ(r.next(), static_cast<std::uint32_t>(random())) << i;
}
#endif

TEST(Cpsc102, SixteenSamplesPerPixelFollowGlibcRandomAcrossTheImage) {
  // 40×3 pixels (two tiles side by side) over a 4×2 window; a ball fills the middle and a
  // wall is behind it, so the pixels its outline crosses mix the two.
  constexpr int W = 40, H = 3, kSpp = 16;
  const Scene s = scene_from(R"(
    camera c { pixeldim 40 3 worlddim 4 2 viewpoint 2 1 5 }
    material ball { ambient 6 0 0 }
    material wall { ambient 0 16 0 }
    sphere { material ball center 2 1 -5 radius 3 }
    plane { material wall normal 0 0 1 point 0 0 -11 })");
  RenderOptions o = course();
  o.spp = kSpp;
  const Image img = render(s, o, 2);

  // The program's loop: rows from the bottom, x left to right, 16 samples, x's jitter first.
  cpsc102::GlibcRandom random;
  auto R = [](L v) { return static_cast<double>(v); };
  auto jitter = [&] { return R(R(random.next() / 2147483647.0L) - 0.5L); };
  int mixed = 0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      double acc[3] = {0, 0, 0};
      for (int k = 0; k < kSpp; ++k) {
        const double fx = R(x + static_cast<L>(jitter()));
        const double fy = R(y + static_cast<L>(jitter()));
        const L wx = R(static_cast<L>(fx) / (W - 1) * 4), wy = R(static_cast<L>(fy) / (H - 1) * 2);
        // The ray from (2, 1, 5) along d = unit(wx − 2, wy − 1, −5). The ball's centre is 10
        // straight ahead, o − c = (0, 0, 10): b = 20 d.z, c = 100 − 9, near root only.
        const L vx = wx - 2, vy = wy - 1, vz = -5, len = std::sqrt(vx * vx + vy * vy + vz * vz);
        const L dz = vz / len, b = 2 * (10 * dz), disc = b * b - 4 * (100 - 9);
        L colour[3] = {0, 0, 0};
        if (disc > 0) {
          colour[0] = 6 / ((-b - std::sqrt(disc)) / 2);
        } else {
          colour[1] = 16 / (-16 / dz);  // the wall z = −11 is 16 below the eye
        }
        for (int c = 0; c < 3; ++c) acc[c] = R(acc[c] + colour[c]);
      }
      const double inv = R(1.0L / kSpp);
      for (int c = 0; c < 3; ++c)
        EXPECT_EQ(at(img, x, y, c), trunc_byte(R(static_cast<L>(acc[c]) * inv)))
            << x << "," << y << "," << c;
      mixed += at(img, x, y, 0) > 0 && at(img, x, y, 1) > 0;
    }
  EXPECT_GE(mixed, 8) << "the outline must cross pixels, or the jitter is not tested";
}

}  // namespace
}  // namespace rayfarm
