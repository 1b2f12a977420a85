// The byte cutoff (Tracer::byte_settled): with one sample a pixel, a path stops once the rays it
// has yet to follow cannot change its pixel's byte. Against the whole path, pixel by pixel:
// the same bytes in both precisions and both roundings, in halls of mirrors, translucent
// mirrors taken heaviest first, a budget that binds, and transparencies at the edge of what
// the bounds allow; and the cutoff really leaves rays out.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "render/film.h"
#include "render/lecture_pipeline.h"
#include "render/prepared_scene.h"
#include "test_util.h"

namespace rayfarm {
namespace {

using test::render;
using test::scene_from;

// Two facing mirrors with spheres between them: chains of reflections, bright ambients that
// saturate and dim ones that do not.
const std::string kMirrors = R"(
camera c { pixeldim 48 36 worlddim 8 6 viewpoint 4 3 6 }
material mirror { ambient .1 diffuse .05 specular .4 }
material chrome { ambient 2 diffuse .1 specular .8 .7 .6 shininess 40 }
material red { ambient 9 1 1 diffuse .8 .1 .1 specular .3 }
material dim { ambient .4 diffuse .3 specular .5 }
light { location 2 5 -1 emissivity 4 }
light { location 7 1 -3 emissivity 2 3 4 }
plane { material mirror normal 0 0 1 point 0 0 -9 }
plane { material mirror normal 0 0 1 point 0 0 8 }
sphere { material chrome center 2 2 -5 radius 1.2 }
sphere { material red center 5.5 3 -6 radius 1 }
sphere { material dim center 4 1 -3 radius .7 }
)";

// Translucent reflective balls before a mirror: rays reflect inside a ball to the depth limit,
// each bounce sending a ray out through the surface. `TR` is the glass's transparency.
std::string glass(const std::string& tr) {
  return "camera c { pixeldim 48 36 worlddim 8 6 viewpoint 4 3 6 }\n"
         "material glass { ambient .5 1 1.5 diffuse .3 .6 .9 specular .2 shininess 60 "
         "transparency " + tr + " }\n"
         "material gold { ambient 2 1.5 .3 diffuse .9 .7 .2 specular .3 .3 .25 shininess 30 }\n"
         "material mirror { ambient .2 diffuse .05 specular .85 }\n"
         "material floor { ambient 1.5 diffuse .8 specular .2 }\n"
         "light { location 1 7 2 emissivity 5 }\n"
         "light { location 6 4 -1 emissivity 2 2 3 }\n"
         "plane { material floor normal 0 1 0 point 0 0 0 }\n"
         "plane { material mirror normal 0 0 1 point 0 0 -11 }\n"
         "sphere { material glass center 2.6 1.2 -5 radius 1.2 }\n"
         "sphere { material glass center 5 1.5 -7 radius 1.4 }\n"
         "sphere { material gold center 6 .8 -4 radius .8 }\n";
}

// glass(tr) with a row of small balls on a floor that lets light through too: enough spheres
// for the hierarchy and for mirror bins, which hand the reflection of a primary ray's hit on a
// plane its closest hit (and not the ray that goes on through the floor).
std::string glass_and_balls(const std::string& tr) {
  std::string text = glass(tr);
  const std::string floor = "material floor { ambient 1.5 diffuse .8 specular .2";
  text.replace(text.find(floor), floor.size(), floor + " transparency .3");
  for (int i = 0; i < 10; ++i)
    text += "sphere { material " + std::string(i % 2 ? "gold" : "glass") + " center " +
            std::to_string(0.5 + 0.8 * i) + " .3 " + std::to_string(-2.5 - 0.4 * i) +
            " radius .3 }\n";
  return text;
}

// A stack of ten parallel planes of one material.
std::string stack(const std::string& material) {
  std::string text = "camera c { pixeldim 4 3 worlddim 8 6 viewpoint 4 3 6 }\n"
                     "material m { " + material + " }\nlight l { location 4 3 2 }\n";
  for (int i = 1; i <= 10; ++i)
    text += "plane { material m normal 0 0 1 point 0 0 -" + std::to_string(i) + " }\n";
  return text;
}

struct Traced {
  int differ = 0;     // pixels whose bytes differ from the whole path's
  RayCounts whole, cut;
};

// Every pixel traced whole and with the cutoff, as a render of one sample a pixel traces it.
template <class T>
Traced trace_both(const Scene& scene, const RenderOptions& o) {
  const LecturePipeline<T> pipe(prepare_scene<T>(scene, o, 0, 1));
  const PreparedScene<T>& p = pipe.scene();
  EXPECT_TRUE(p.features.byte_cutoff);
  const Film film{o.effective_rounding(), false};
  Tracer<T> whole(p), cut(p);
  cut.stop_at_settled_bytes(film);
  Traced out;
  for (int r = 0; r < pipe.height(); ++r)
    for (int x = 0; x < pipe.width(); ++x) {
      const Vec3<T> point = pipe.screen_point_of(x, r, 0);
      const Vec3<T> a = whole.primary(point), b = cut.primary(point);
      bool same = true;
      for (int k = 0; k < 3; ++k)
        same = same && film.to_byte(static_cast<double>(a[k])) ==
                           film.to_byte(static_cast<double>(b[k]));
      out.differ += !same;
    }
  out.whole = whole.counts;
  out.cut = cut.counts;
  return out;
}

void expect_exact_and_fewer(const Scene& scene, RenderOptions o, bool fewer) {
  for (const char* rounding : {"nearest", "truncate"})
    for (Precision precision : {Precision::f64, Precision::f32}) {
      SCOPED_TRACE(std::string(rounding) + " " + std::string(to_string(precision)));
      ASSERT_FALSE(apply_option(o, "rounding", rounding));
      o.precision = precision;
      const Traced t = precision == Precision::f64 ? trace_both<double>(scene, o)
                                                   : trace_both<float>(scene, o);
      EXPECT_EQ(t.differ, 0);
      EXPECT_EQ(t.cut.primary, t.whole.primary);
      EXPECT_LE(t.cut.shadow, t.whole.shadow);
      if (fewer) {
        EXPECT_LT(t.cut.reflection, t.whole.reflection);
      } else {
        EXPECT_LE(t.cut.reflection, t.whole.reflection);
      }
      // And the render itself, against one with every specialization off.
      RenderStats stats;
      const Image fast = render(scene, o, 2, &stats);
      EXPECT_NE(std::find(stats.parts.begin(), stats.parts.end(), "byte-cutoff"),
                stats.parts.end());
      RenderOptions plain = o;
      plain.specialize = false;
      EXPECT_EQ(fast, render(scene, plain, 2));
    }
}

TEST(ByteCutoff, MirrorChainsStopAtTheirBytesAndKeepThem) {
  const Scene s = scene_from(kMirrors);
  RenderOptions o;
  expect_exact_and_fewer(s, o, true);
  o.max_depth = 30;
  expect_exact_and_fewer(s, o, true);
}

TEST(ByteCutoff, TranslucentPathsTakenHeaviestFirstKeepTheirBytes) {
  // 0.6 as in the course's scenes; 1 - 2^-8, the largest transparency short of 1 the bounds
  // take; exactly 1, no local colour kept at all.
  for (const char* tr : {"0.6", "0.99609375", "1"}) {
    SCOPED_TRACE(tr);
    expect_exact_and_fewer(scene_from(glass(tr)), RenderOptions{}, true);
  }
  // The first bounce's closest hit from the mirror bins goes with that bounce, whenever it is
  // taken.
  const Scene balls = scene_from(glass_and_balls("0.6"));
  RenderStats stats;
  render(balls, RenderOptions{}, 1, &stats);
  for (const char* part : {"bvh", "mirror-bins", "transparency", "byte-cutoff"})
    EXPECT_NE(std::find(stats.parts.begin(), stats.parts.end(), part), stats.parts.end()) << part;
  expect_exact_and_fewer(balls, RenderOptions{}, true);
}

TEST(ByteCutoff, PathsThroughTranslucentObjectsThatDoNotReflectStopToo) {
  // No specular anywhere: only transmitted rays to leave out, each crossing weighing 0.3.
  const Scene s = scene_from(R"(
camera c { pixeldim 48 36 worlddim 8 6 viewpoint 4 3 6 }
material veil { ambient 1 2 3 diffuse .6 .5 .4 transparency .3 }
material floor { ambient 2 diffuse .7 }
light { location 3 6 2 emissivity 4 }
plane { material floor normal 0 1 0 point 0 0 0 }
sphere { material veil center 4 3 -3 radius 1.5 }
sphere { material veil center 4 3 -6 radius 2 }
sphere { material veil center 3.5 2.5 -9 radius 2.5 }
)");
  expect_exact_and_fewer(s, RenderOptions{}, true);
}

TEST(ByteCutoff, DeepBranchingPathsKeepTheirBytesWhetherTheBudgetCanBindOrNot) {
  // max_depth 16: a path could outgrow the budget of levels, so the rays are taken in the
  // plain order, and only the chains of reflections stop.
  RenderOptions deep;
  deep.max_depth = 16;
  expect_exact_and_fewer(scene_from(glass("0.6")), deep, true);
  // A stack of translucent mirrors, which reaches the budget: at least the same bytes.
  RenderOptions o;
  o.max_depth = 40;
  expect_exact_and_fewer(scene_from(test::translucent_mirror_stack()), o, false);
  // At max_depth 12 it cannot: the rays are taken heaviest first while a path has few levels,
  // then (past what the bounds fold) last in, first out, thousands of them a pixel.
  o.max_depth = 12;
  expect_exact_and_fewer(scene_from(test::translucent_mirror_stack()), o, false);
  // Reflected and transmitted rays of unequal weights, where the budget binds: taken heaviest
  // first, other rays would meet the budget than in the plain order.
  o.max_depth = 20;
  expect_exact_and_fewer(
      scene_from(stack("ambient 1 diffuse .5 .7 .9 specular .9 transparency .5")), o, false);
}

TEST(ByteCutoff, OnlyWhereEachSampleIsItsPixelsByteAndTheBoundsHold) {
  auto has_cutoff = [](const Scene& s, RenderOptions o) {
    RenderStats stats;
    render(s, o, 1, &stats);
    return std::find(stats.parts.begin(), stats.parts.end(), "byte-cutoff") != stats.parts.end();
  };
  const Scene mirrors = scene_from(kMirrors);
  RenderOptions o;
  EXPECT_TRUE(has_cutoff(mirrors, o));
  o.spp = 4;  // the byte is the mean of four samples
  EXPECT_FALSE(has_cutoff(mirrors, o));
  o = {};
  o.specialize = false;
  EXPECT_FALSE(has_cutoff(mirrors, o));
  o = {};
  o.max_depth = 0;  // no reflection rays
  EXPECT_FALSE(has_cutoff(mirrors, o));
  // A transparency just short of 1: keep·local + filter·value could round above the bound.
  EXPECT_FALSE(has_cutoff(scene_from(glass("0.999")), RenderOptions{}));
  EXPECT_TRUE(has_cutoff(scene_from(glass("0.99")), RenderOptions{}));
  // A subnormal diffuse: transparency · diffuse rounds up to all of it, a filter of 1 beside a
  // keep of 0.4, and a level that only lets light through could pass the bound.
  EXPECT_FALSE(has_cutoff(
      scene_from(stack("ambient 100 diffuse 5e-324 specular .003 transparency .6")), {}));
  EXPECT_TRUE(has_cutoff(
      scene_from(stack("ambient 100 diffuse 1e-300 specular .003 transparency .6")), {}));
}

}  // namespace
}  // namespace rayfarm
