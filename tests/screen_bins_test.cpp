// Primary rays answered from screen bins: every pixel whose ray the tracer's sphere test says
// hits a sphere lies in that sphere's rectangle, in the bin of its tile; and renders with the
// bins equal the plain loop's byte for byte for every camera placement (spheres in front of,
// around and behind the eye, an eye looking either way along z), image shape, sampling and
// distance cap, in both precisions.
#include "accel/screen_bins.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>

#include "render/prepared_scene.h"
#include "random_scene.h"
#include "rayfarm/render.h"
#include "render/tracer.h"

namespace rayfarm {
namespace {

using test::random_scene;
using test::Rng;

bool has_part(const RenderStats& st, const std::string& part) {
  return std::find(st.parts.begin(), st.parts.end(), part) != st.parts.end();
}

template <class T>
void expect_rectangles_cover_every_hit(const Scene& scene, int width, int height) {
  RenderOptions o;
  o.width = width;
  o.height = height;
  const PreparedScene<T> p = prepare_scene<T>(scene, o, 0);
  ASSERT_TRUE(p.features.screen_bins);
  const ScreenBins& bins = p.screen_bins;
  // Each (tile, sphere) pair's rectangle.
  std::map<std::pair<int, int>, const ScreenBinEntry*> entry;
  for (int t = 0; t < bins.tiles_x * bins.tiles_y; ++t)
    for (const ScreenBinEntry& e : bins.of_tile(t)) entry[{t, e.sphere}] = &e;
  const Tracer<T> tracer(p);
  int hits = 0;
  for (int r = 0; r < height; ++r) {
    for (int x = 0; x < width; ++x) {
      const int y = height - 1 - r;
      auto frac = [](int i, int n) { return n == 1 ? T(0.5) : static_cast<T>(i) / static_cast<T>(n - 1); };
      const Vec3<T> target(frac(x, width) * p.world_width, frac(y, height) * p.world_height, 0);
      const auto d = tracer.primary_direction(target);
      ASSERT_TRUE(d);
      const int tile = (r / kTileSize) * bins.tiles_x + x / kTileSize;
      for (int i = 0; i < static_cast<int>(p.spheres.size()); ++i) {
        const T t = sphere_t(p.eye, *d, p.spheres[i].centre, p.spheres[i].radius, i, Origin{});
        if (!(t > 0)) continue;
        ++hits;
        auto it = entry.find({tile, i});
        ASSERT_NE(it, entry.end()) << "sphere " << i << " hits pixel " << x << "," << r;
        const ScreenBinEntry& e = *it->second;
        EXPECT_TRUE(x >= e.x0 && x <= e.x1 && r >= e.r0 && r <= e.r1)
            << "sphere " << i << " pixel " << x << "," << r;
        EXPECT_LE(static_cast<double>(e.near), static_cast<double>(t));
      }
    }
  }
  EXPECT_GT(hits, width * height / 10);
}

TEST(ScreenBins, RectanglesHoldEveryPixelTheSphereTestHits) {
  Rng rng(21);
  Scene scene = random_scene(rng, 400, 4);
  scene.cameras[0].viewpoint = {0, 0, 12};
  expect_rectangles_cover_every_hit<double>(scene, 80, 60);
  expect_rectangles_cover_every_hit<float>(scene, 80, 60);
  scene.cameras[0].viewpoint = {0.5, -0.25, 1};  // among the spheres
  expect_rectangles_cover_every_hit<double>(scene, 70, 50);
  expect_rectangles_cover_every_hit<float>(scene, 70, 50);
}

struct CameraCase {
  const char* what;
  glm::dvec3 eye;
  double world_width, world_height;
};

TEST(ScreenBins, RendersEqualTheLoopForEveryCameraShapeAndSampling) {
  Rng rng(22);
  Scene scene = random_scene(rng, 500, 4);
  scene.materials[0].specular = glm::dvec3(0.4);  // reflections and highlights too
  const CameraCase cameras[] = {
      {"in front", {0, 0, 12}, 8, 6},
      {"among the spheres", {0.3, 0.2, 0.9}, 8, 6},
      {"looking towards +z", {1, -1, -12}, 6, 6},
      {"narrow window far away", {2, 2, 400}, 0.05, 0.04},
  };
  struct Shape {
    int width, height, spp;
    double max_dist;
  };
  const Shape shapes[] = {{45, 37, 1, 0}, {1, 1, 1, 0}, {1, 29, 2, 0}, {40, 30, 3, 0}, {40, 30, 1, 14}};
  int binned = 0;
  for (const CameraCase& c : cameras) {
    SCOPED_TRACE(c.what);
    scene.cameras[0].viewpoint = c.eye;
    scene.cameras[0].world_width = c.world_width;
    scene.cameras[0].world_height = c.world_height;
    for (const Shape& shape : shapes) {
      for (Precision precision : {Precision::f64, Precision::f32}) {
        RenderOptions o;
        o.width = shape.width;
        o.height = shape.height;
        o.spp = shape.spp;
        if (shape.max_dist > 0) o.max_dist = shape.max_dist;
        o.precision = precision;
        RenderStats stats;
        const Image fast = render_image(scene, o, 2, &stats);
        binned += has_part(stats, "screen-bins");
        o.specialize = false;
        ASSERT_EQ(render_image(scene, o, 1), fast)
            << shape.width << "x" << shape.height << " spp " << shape.spp;
      }
    }
  }
  EXPECT_GE(binned, 30);  // the far narrow window may decline, the rest must not
}

TEST(ScreenBins, DeclineAnEyeInTheScreenPlaneAndTooMuchCoverage) {
  const std::vector<WidenedSphere> spheres{{{1, 1, -3}, 0.5}, {{2, 1, -1}, 0.25}};
  ScreenCamera cam{{2, 1.5, 5}, 4, 3, 64, 48, 1.5, 1.5};
  const ScreenBins bins = build_screen_bins(cam, spheres, 32, 64);
  ASSERT_FALSE(bins.empty());
  EXPECT_EQ(bins.tiles_x, 2);
  EXPECT_EQ(bins.tiles_y, 2);
  EXPECT_TRUE(build_screen_bins(cam, spheres, 32, 0.01).empty());
  cam.eye.z = 0;
  EXPECT_TRUE(build_screen_bins(cam, spheres, 32, 64).empty());
}

TEST(ScreenBins, SpheresBehindTheEyeAreLeftOutAndOnesAroundItCoverTheScreen) {
  const std::vector<WidenedSphere> spheres{{{2, 1.5, 9}, 1}, {{2, 1.5, 5}, 0.5}};
  const ScreenCamera cam{{2, 1.5, 5}, 4, 3, 64, 48, 1.5, 1.5};
  const ScreenBins bins = build_screen_bins(cam, spheres, 32, 64);
  ASSERT_EQ(bins.entries.size(), 4u);  // only the sphere around the eye, in all four tiles
  for (const ScreenBinEntry& e : bins.entries) {
    EXPECT_EQ(e.sphere, 1);
    EXPECT_EQ(e.x0, 0);
    EXPECT_EQ(e.x1, 63);
    EXPECT_EQ(e.r0, 0);
    EXPECT_EQ(e.r1, 47);
  }
}

TEST(ScreenBins, SpheresBesideTheEyeReachOnlyTheirSideOfTheScreen) {
  // Both cut the eye's plane z = 5; one is far to the side, one near it on the right.
  const std::vector<WidenedSphere> spheres{{{12, 1.5, 5}, 0.5}, {{2.6, 1.5, 4.9}, 0.5}};
  const ScreenCamera cam{{2, 1.5, 5}, 4, 3, 64, 48, 0.5, 0.5};
  const ScreenBins bins = build_screen_bins(cam, spheres, 32, 64);
  ASSERT_EQ(bins.entries.size(), 2u);  // the near one, in the two tiles on the right
  for (const ScreenBinEntry& e : bins.entries) {
    EXPECT_EQ(e.sphere, 1);
    // Its points to the right of the eye by 0.1 or more, at w <= 0.12: x >= 2 + 0.1 / 0.12.
    EXPECT_EQ(e.x0, 44);
    EXPECT_EQ(e.x1, 63);
    EXPECT_EQ(e.r0, 0);
    EXPECT_EQ(e.r1, 47);
  }
}

TEST(ScreenBins, RectanglesHoldEveryPixelWithTheEyeInsideTheCloud) {
  Rng rng(23);
  Scene scene = random_scene(rng, 1500, 4);
  scene.cameras[0].viewpoint = {0.2, -0.1, 0.3};  // spheres on every side, many cut its plane
  expect_rectangles_cover_every_hit<double>(scene, 80, 60);
  expect_rectangles_cover_every_hit<float>(scene, 80, 60);
}

}  // namespace
}  // namespace rayfarm
