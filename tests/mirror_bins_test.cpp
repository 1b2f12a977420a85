// Reflection rays off planes answered from mirror bins: for every pixel whose primary ray
// hits a reflective plane, every sphere the tracer's sphere test says its reflection ray hits
// is in the mirror bin of its tile, with a rectangle holding the pixel and a near bound below
// the hit; and renders with the bins equal the plain loop's byte for byte for floors, walls
// and tilted mirrors, spheres resting on and cutting through the plane, grazing views, jittered
// supersampling, distance caps, depth and bailout limits, in both precisions.
#include "accel/mirror_bins.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "random_scene.h"
#include "rayfarm/render.h"
#include "render/lecture_pipeline.h"
#include "render/prepared_scene.h"
#include "render/tracer.h"

namespace rayfarm {
namespace {

using test::Rng;

bool has_part(const RenderStats& st, const std::string& part) {
  return std::find(st.parts.begin(), st.parts.end(), part) != st.parts.end();
}

// A cloud of spheres in front of the screen, as random_scene makes them (radii over a decade
// and more, coincident and touching pairs), over `plane`, which mirrors; material 0, which
// the spheres share, reflects too.
Scene mirror_scene(Rng& rng, int count, const Plane& plane, double specular = 0.5) {
  Scene s = test::base_scene();
  s.materials[0].specular = glm::dvec3(0.3);
  Material mirror;
  mirror.name = "mirror";
  mirror.ambient = glm::dvec3(0.4);
  mirror.diffuse = glm::dvec3(0.2);
  mirror.specular = glm::dvec3(specular);
  s.materials.push_back(mirror);
  Light second;
  second.name = "second";
  second.location = {9, 5, 2};
  s.lights.push_back(second);
  for (int i = 0; i < count; ++i) {
    const double r = std::exp(rng.in(std::log(0.03), std::log(0.6)));
    if (i > 0 && rng.chance(0.1)) {  // coincident with an earlier sphere
      const Sphere& twin = test::sphere_at(s, rng.below(i));
      test::add_sphere(s, twin.center, twin.radius);
    } else if (i > 0 && rng.chance(0.1)) {  // touching an earlier sphere from outside
      const Sphere& other = test::sphere_at(s, rng.below(i));
      test::add_sphere(s, other.center + (other.radius + r) * rng.direction(), r);
    } else {
      test::add_sphere(s, {rng.in(-3, 11), rng.in(-0.5, 6.5), rng.in(-16, 0)}, r);
    }
  }
  Object& floor = s.objects.emplace_back();
  floor.name = "mirror";
  floor.kind = EntityKind::plane;
  floor.shape = plane;
  floor.material = 1;
  return s;
}

// Every reflection ray the bins answer: each sphere its sphere test hits is listed.
template <class T>
void expect_bins_hold_every_hit(const Scene& scene, int width, int height, int spp) {
  RenderOptions o;
  o.width = width;
  o.height = height;
  o.spp = spp;
  const LecturePipeline<T> pipeline(prepare_scene<T>(scene, o, 0));
  const PreparedScene<T>& p = pipeline.scene();
  ASSERT_TRUE(p.features.mirror_bins);
  const int plane = p.plane_base();  // the mirror is the only plane
  const ScreenBins& bins = p.mirror_bins.at(0);
  ASSERT_FALSE(bins.empty());
  std::map<std::pair<int, int>, const ScreenBinEntry*> entry;
  for (int t = 0; t < bins.tiles_x * bins.tiles_y; ++t)
    for (const ScreenBinEntry& e : bins.of_tile(t)) entry[{t, e.sphere}] = &e;
  const Tracer<T> tracer(p);
  int bounces = 0, hits = 0;
  for (int pass = 0; pass < spp; ++pass) {
    for (int r = 0; r < height; ++r) {
      for (int x = 0; x < width; ++x) {
        const auto d = tracer.primary_direction(pipeline.screen_point_of(x, r, pass));
        ASSERT_TRUE(d);
        const Hit<T> first = tracer.closest(p.eye, *d, Origin{}, p.max_dist);
        if (first.object != plane) continue;
        const auto bounce = tracer.primary_bounce(*d, first);
        ASSERT_TRUE(bounce);
        const glm::dvec3 a = glm::abs(glm::dvec3(bounce->origin));
        if (!(std::max({a.x, a.y, a.z}) <= p.mirror_reach)) continue;
        ++bounces;
        const int tile = (r / kTileSize) * bins.tiles_x + x / kTileSize;
        for (int i = 0; i < static_cast<int>(p.spheres.size()); ++i) {
          const T t = sphere_t(bounce->origin, bounce->dir, p.spheres[i].centre,
                               p.spheres[i].radius, i, bounce->from);
          if (!(t > 0)) continue;
          ++hits;
          auto it = entry.find({tile, i});
          ASSERT_NE(it, entry.end()) << "sphere " << i << " pixel " << x << "," << r;
          const ScreenBinEntry& e = *it->second;
          EXPECT_TRUE(x >= e.x0 && x <= e.x1 && r >= e.r0 && r <= e.r1)
              << "sphere " << i << " pixel " << x << "," << r;
          EXPECT_LE(mirror_near(e.near, static_cast<double>(first.t), p.mirror_slack),
                    static_cast<double>(t))
              << "sphere " << i << " pixel " << x << "," << r;
        }
      }
    }
  }
  EXPECT_GT(bounces, width * height / 8);
  EXPECT_GT(hits, 10);
}

struct PlaneCase {
  const char* what;
  Plane plane;
  glm::dvec3 eye;
};

// Planes the eye sees from either side, at every angle; spheres above, on and through them.
const PlaneCase kPlanes[] = {
    {"floor", {{0, 1, 0}, {0, 0, 0}}, {4, 3, 5}},
    {"floor through the spheres", {{0, 1, 0}, {0, 1.5, 0}}, {4, 3, 5}},
    {"floor seen from high up", {{0, 2, 0}, {0, 0, 0}}, {4, 9, 3}},
    {"ceiling seen from below", {{0, -1, 0}, {0, 5, 0}}, {4, 3, 5}},
    {"back wall", {{0, 0, 1}, {0, 0, -12}}, {4, 3, 5}},
    {"tilted", {{0.3, 0.8, 0.5}, {4, 0, -8}}, {4, 3, 5}},
    {"grazing: the eye just above the floor", {{0, 1, 0}, {0, 2.95, 0}}, {4, 3, 5}},
    {"the eye among the spheres", {{0, 1, 0}, {0, 0, 0}}, {4, 3, 0.3}},
};

TEST(MirrorBins, BinsHoldEverySphereAReflectionRayHits) {
  for (const PlaneCase& c : kPlanes) {
    SCOPED_TRACE(c.what);
    Rng rng(31);
    Scene scene = mirror_scene(rng, 400, c.plane);
    scene.cameras[0].viewpoint = c.eye;
    expect_bins_hold_every_hit<double>(scene, 64, 48, 1);
    expect_bins_hold_every_hit<float>(scene, 64, 48, 1);
    expect_bins_hold_every_hit<double>(scene, 40, 30, 3);
    expect_bins_hold_every_hit<float>(scene, 40, 30, 3);
  }
}

TEST(MirrorBins, RendersEqualTheLoopForEveryPlaneCameraAndSampling) {
  struct Shape {
    int width, height, spp;
    double max_dist;
  };
  const Shape shapes[] = {{45, 37, 1, 0}, {1, 1, 1, 0}, {1, 29, 2, 0}, {40, 30, 3, 0},
                          {40, 30, 1, 14}};
  int mirrored = 0, renders = 0;
  for (const PlaneCase& c : kPlanes) {
    SCOPED_TRACE(c.what);
    Rng rng(32);
    Scene scene = mirror_scene(rng, 500, c.plane);
    scene.cameras[0].viewpoint = c.eye;
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
        // One-column images: every rectangle covers the column, which costs more than it saves.
        if (shape.width > 1) {
          mirrored += has_part(stats, "mirror-bins");
          ++renders;
        }
        o.specialize = false;
        ASSERT_EQ(render_image(scene, o, 1), fast)
            << shape.width << "x" << shape.height << " spp " << shape.spp;
      }
    }
  }
  EXPECT_EQ(mirrored, renders);
}

TEST(MirrorBins, RendersEqualTheLoopWithDepthBailoutShadowsOffAndTiles) {
  Rng rng(33);
  Scene scene = mirror_scene(rng, 300, {{0, 1, 0}, {0, 0, 0}}, 0.25);
  // A second, tiled mirror on the left whose other material does not reflect.
  Material dull;
  dull.name = "dull";
  dull.ambient = glm::dvec3(1);
  dull.diffuse = glm::dvec3(0.5);
  scene.materials.push_back(dull);
  Object& wall = scene.objects.emplace_back();
  wall.name = "wall";
  wall.kind = EntityKind::tiled_plane;
  wall.material = 1;  // the mirror
  TiledPlane tiles;
  tiles.plane = Plane{{1, 0, 0}, {-1, 0, 0}};
  tiles.alt_material = static_cast<int>(scene.materials.size()) - 1;
  tiles.tile = {{0, 0, 1}, 0.7, 0.5};
  wall.shape = tiles;
  RenderOptions base;
  base.width = 48;
  base.height = 36;
  std::vector<RenderOptions> variants;
  for (int depth : {1, 2, 8}) {
    RenderOptions o = base;
    o.max_depth = depth;
    variants.push_back(o);
  }
  RenderOptions bail = base;
  bail.bailout = 0.3;  // the floor's reflection (0.25) is below it: no mirror bins
  variants.push_back(bail);
  RenderOptions dark = base;
  dark.shadows = false;
  variants.push_back(dark);
  RenderOptions sampled = base;
  sampled.spp = 4;
  sampled.seed = 7;
  variants.push_back(sampled);
  for (const RenderOptions& v : variants) {
    for (Precision precision : {Precision::f64, Precision::f32}) {
      RenderOptions o = v;
      o.precision = precision;
      RenderStats stats;
      const Image fast = render_image(scene, o, 2, &stats);
      EXPECT_EQ(has_part(stats, "mirror-bins"), v.bailout == 0);
      o.specialize = false;
      ASSERT_EQ(render_image(scene, o, 1), fast) << canonical_string(v);
    }
  }
}

TEST(MirrorBins, BinsHoldEveryHitAndRendersEqualTheLoopAtExtremeScales) {
  for (double k : {1e-6, 1e6}) {
    SCOPED_TRACE(k);
    Rng rng(34);
    Scene scene = mirror_scene(rng, 300, {{0, 1, 0}, {0, 0.5, 0}});
    for (Object& o : scene.objects) {
      if (Sphere* sp = std::get_if<Sphere>(&o.shape)) {
        sp->center *= k;
        sp->radius *= k;
      }
      if (Plane* pl = std::get_if<Plane>(&o.shape)) pl->point *= k;
    }
    for (Light& l : scene.lights) l.location *= k;
    Camera& cam = scene.cameras[0];
    cam.viewpoint *= k;
    cam.world_width *= k;
    cam.world_height *= k;
    expect_bins_hold_every_hit<double>(scene, 48, 36, 1);
    expect_bins_hold_every_hit<float>(scene, 48, 36, 2);
    for (Precision precision : {Precision::f64, Precision::f32}) {
      RenderOptions o;
      o.width = 40;
      o.height = 30;
      o.precision = precision;
      RenderStats stats;
      const Image fast = render_image(scene, o, 2, &stats);
      EXPECT_TRUE(has_part(stats, "mirror-bins"));
      o.specialize = false;
      ASSERT_EQ(render_image(scene, o, 1), fast);
    }
  }
}

TEST(MirrorBins, DeclineAnEyeInThePlane) {
  const std::vector<WidenedSphere> spheres{{{1, 1, -3}, 0.5}, {{2, 1, -1}, 0.25}};
  const ScreenCamera cam{{2, 1.5, 5}, 4, 3, 64, 48, 1.5, 1.5};
  EXPECT_FALSE(build_mirror_bins(cam, spheres, {0, 1, 0}, {0, 0, 0}, 32, 64).empty());
  EXPECT_TRUE(build_mirror_bins(cam, spheres, {0, 1, 0}, {0, 1.5, 0}, 32, 64).empty());
}

TEST(MirrorBins, ListMirrorImages) {
  // A sphere above a floor at y = 0 is listed where its image below the floor is seen.
  const std::vector<WidenedSphere> spheres{{{2, 1, -3}, 0.5}};
  const ScreenCamera cam{{2, 1.5, 5}, 4, 3, 64, 48, 0.5, 0.5};
  const ScreenBins direct = build_screen_bins(cam, spheres, 32, 64);
  const ScreenBins mirrored = build_mirror_bins(cam, spheres, {0, 2, 0}, {7, 0, 1}, 32, 64);
  const std::vector<WidenedSphere> image{{{2, -1, -3}, 0.5}};
  const ScreenBins expected = build_screen_bins(cam, image, 32, 64);
  ASSERT_FALSE(mirrored.empty());
  ASSERT_EQ(mirrored.entries.size(), expected.entries.size());
  for (std::size_t i = 0; i < expected.entries.size(); ++i) {
    EXPECT_EQ(mirrored.entries[i].r0, expected.entries[i].r0);
    EXPECT_EQ(mirrored.entries[i].r1, expected.entries[i].r1);
    EXPECT_EQ(mirrored.entries[i].near, expected.entries[i].near);
  }
  EXPECT_GT(mirrored.entries[0].r0, direct.entries[0].r1);  // lower in the image
}

}  // namespace
}  // namespace rayfarm
