// Shadow rays answered from a light buffer are answered exactly as by the plain loop: from
// every kind of shading point (sphere outsides and insides, the floor, coincident and
// touching spheres), for lights outside the spheres, among them, inside one and on one,
// for segments grazing the spheres' silhouettes, at extreme scales, in both precisions.
#include "accel/light_buffer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <tuple>

#include "render/prepared_scene.h"
#include "rayfarm/render.h"
#include "random_scene.h"
#include "render/tracer.h"

namespace rayfarm {
namespace {

using test::random_scene;
using test::Rng;

// The plain loop's scene and the specialized one (hierarchy, light buffers) side by side.
template <class T>
struct Pair {
  PreparedScene<T> loop;
  PreparedScene<T> fast;
};

template <class T>
Pair<T> prepare_both(const Scene& scene) {
  RenderOptions o;
  o.specialize = false;
  Pair<T> p{prepare_scene<T>(scene, o, 0), {}};
  o.specialize = true;
  p.fast = prepare_scene<T>(scene, o, 0);
  return p;
}

// The four kinds of light position; the random scenes fill [-extent, extent]^3.
void add_lights(Scene& s, double extent) {
  s.lights.clear();
  auto add = [&](const char* name, glm::dvec3 at) {
    Light& l = s.lights.emplace_back();
    l.name = name;
    l.location = at;
  };
  add("outside", {0, 3 * extent, 0.5 * extent});
  add("among", {0.1 * extent, 0.2 * extent, -0.3 * extent});
  const Sphere& a = test::sphere_at(s, 0);
  add("inside", a.center + glm::dvec3(0.3 * a.radius, 0, 0));
  const Sphere& b = test::sphere_at(s, 1);
  add("on", b.center + glm::dvec3(0, b.radius, 0));
}

std::string light_name(const Scene& s, std::size_t i) { return s.lights[i].name; }

struct Counts {
  int rays = 0;
  int blocked = 0;
  int answered = 0;  // by the buffer, not its fallback
};

// A shadow ray to each light from the hit point of each random ray, as the tracer sends it.
template <class T>
Counts expect_same_shadows(const Scene& scene, Rng& rng, double extent, int rays) {
  const Pair<T> p = prepare_both<T>(scene);
  EXPECT_TRUE(p.fast.features.light_buffers);
  EXPECT_EQ(p.fast.blockers_in_leaf_order, !p.fast.bvh.empty());
  EXPECT_TRUE(p.loop.light_buffers.empty());
  const Tracer<T> loop(p.loop), fast(p.fast);
  const int ns = static_cast<int>(p.loop.spheres.size());
  const T inf = std::numeric_limits<T>::infinity();
  Counts n;
  for (int i = 0; i < rays; ++i) {
    const Vec3<T> o(rng.point(rng.chance(0.3) ? 3 * extent : extent));
    const Vec3<T> d(rng.direction());
    const Hit<T> hit = loop.closest(o, d, {}, inf);
    if (hit.object < 0) continue;
    const Vec3<T> x = o + hit.t * d;
    const Vec3<T> normal =
        hit.object < ns ? x - p.loop.spheres[hit.object].centre : p.loop.planes[hit.object - ns].normal;
    const Origin from{hit.object, glm::dot(normal, d) > 0};
    for (std::size_t l = 0; l < p.loop.lights.size(); ++l) {
      const PreparedLight<T>& light = p.loop.lights[l];
      Vec3<T> to = light.location - x;
      const T r = glm::length(to);
      if (!(r > 0)) continue;
      to /= r;
      const T dist = r * (1 - 64 * std::numeric_limits<T>::epsilon());
      const LightBuffer& buffer = p.fast.light_buffers[l];
      const bool expected = loop.occluded(x, to, from, dist);
      const bool got = fast.occluded(x, to, from, dist, nullptr, &buffer);
      EXPECT_EQ(got, expected) << "ray " << i << " light " << light_name(scene, l)
                               << " from object " << hit.object;
      if (got != expected) return n;
      LightBuffer::Cell cell;
      n.answered += !buffer.empty() && buffer.lookup(glm::dvec3(x), cell);
      n.blocked += expected;
      ++n.rays;
    }
  }
  return n;
}

Scene scaled(Scene s, double k) {
  for (Object& o : s.objects) {
    if (Sphere* sp = std::get_if<Sphere>(&o.shape)) {
      sp->center *= k;
      sp->radius *= k;
    }
    if (Plane* pl = std::get_if<Plane>(&o.shape)) pl->point *= k;
  }
  for (Light& l : s.lights) l.location *= k;
  return s;
}

TEST(LightBuffer, ShadowsEqualTheLoopForEveryKindOfLightAndShadingPoint) {
  Rng rng(11);
  Scene scene = random_scene(rng, 1500, 4);
  add_lights(scene, 4);
  for (int precision = 0; precision < 2; ++precision) {
    const Counts n = precision ? expect_same_shadows<float>(scene, rng, 4, 3000)
                               : expect_same_shadows<double>(scene, rng, 4, 3000);
    // Both answers occur, and the buffers (not their fallback) gave nearly all of them.
    EXPECT_GT(n.blocked, n.rays / 10);
    EXPECT_LT(n.blocked, n.rays - n.rays / 10);
    EXPECT_GT(n.answered, n.rays * 3 / 4);
  }
}

TEST(LightBuffer, ShadowsEqualTheLoopAtExtremeScales) {
  Rng rng(12);
  Scene scene = random_scene(rng, 800, 4);
  add_lights(scene, 4);
  for (double k : {1e-6, 1e6}) {
    SCOPED_TRACE(k);
    const Scene s = scaled(scene, k);
    EXPECT_GT(expect_same_shadows<double>(s, rng, 4 * k, 1500).answered, 0);
    EXPECT_GT(expect_same_shadows<float>(s, rng, 4 * k, 1500).answered, 0);
  }
}

// Segments from beyond a sphere to the light that pass its centre at the radius to within
// a few hundred ulps, on both sides: the cells must hold the sphere either way.
template <class T>
void expect_grazing_segments_agree(Rng& rng) {
  Scene scene = test::base_scene();
  for (int i = 0; i < 64; ++i) test::add_sphere(scene, rng.point(4), std::exp(rng.in(-5, 0)));
  const glm::dvec3 light(0.5, 9, 0.25);
  scene.lights.assign(1, Light{});
  scene.lights[0].name = "l";
  scene.lights[0].location = light;
  const Pair<T> p = prepare_both<T>(scene);
  ASSERT_FALSE(p.fast.light_buffers.empty());
  const Tracer<T> loop(p.loop), fast(p.fast);
  int blocked = 0, rays = 0;
  for (const Object& o : scene.objects) {
    if (!o.as<Sphere>()) continue;
    const Sphere& s = *o.as<Sphere>();
    const glm::dvec3 axis = glm::normalize(s.center - light);
    const double dist = glm::length(s.center - light);
    for (int k = 0; k < 40; ++k) {
      // A line from the light at sin(angle) = r (1 + a few hundred ulps) / dist from the
      // axis passes the centre at that many ulps of the radius.
      const glm::dvec3 side = glm::normalize(glm::cross(axis, rng.direction()));
      const double off = 1 + rng.in(-300, 300) * std::numeric_limits<T>::epsilon();
      const double sine = std::min(1.0, s.radius * off / dist);
      const glm::dvec3 u = std::sqrt(1 - sine * sine) * axis + sine * side;
      const Vec3<T> x(light + u * rng.in(dist + s.radius * 1.01, 3 * dist + s.radius));
      Vec3<T> to = Vec3<T>(light) - x;
      const T r = glm::length(to);
      to /= r;
      const bool expected = loop.occluded(x, to, {}, r);
      ASSERT_EQ(fast.occluded(x, to, {}, r, nullptr, &p.fast.light_buffers[0]), expected);
      blocked += expected;
      ++rays;
    }
  }
  EXPECT_GT(blocked, rays / 10);
  EXPECT_LT(blocked, rays - rays / 10);
}

TEST(LightBuffer, SegmentsGrazingASphereAgreeWithTheLoop) {
  Rng rng(13);
  expect_grazing_segments_agree<double>(rng);
  expect_grazing_segments_agree<float>(rng);
}

TEST(LightBuffer, ListsSpheresAboutTheLightForEveryRayAndDeclinesWhatItCannotAnswer) {
  const std::vector<WidenedSphere> spheres{{{0, 0, 0}, 1}, {{5, 0, 0}, 1}, {{0, 0, -7}, 2}};
  const LightBuffer lb = build_light_buffer({0.5, 0, 0}, spheres, 100);
  ASSERT_FALSE(lb.empty());
  EXPECT_EQ(lb.around, std::vector<std::int32_t>{0});
  LightBuffer::Cell cell;
  // Towards +x the cell holds sphere 1 (and only it: sphere 2 lies towards -z).
  ASSERT_TRUE(lb.lookup({10, 0, 0}, cell));
  ASSERT_EQ(cell.end - cell.begin, 1);
  EXPECT_EQ(cell.begin->blocker, 1);
  EXPECT_FLOAT_EQ(cell.begin->near, 3.5f);
  ASSERT_TRUE(lb.lookup({0.5, 0, -20}, cell));
  ASSERT_EQ(cell.end - cell.begin, 1);
  EXPECT_EQ(cell.begin->blocker, 2);
  EXPECT_FALSE(lb.lookup({0.5, 0, 0}, cell));   // the light itself: no direction
  EXPECT_FALSE(lb.lookup({101, 0, 0}, cell));   // beyond reach
  EXPECT_FALSE(lb.lookup({NAN, 0, 0}, cell));
}

TEST(LightBuffer, IsNotBuiltWhenTooManySpheresSurroundTheLight) {
  std::vector<WidenedSphere> nested;
  for (int i = 1; i <= 40; ++i) nested.push_back({{0, 0, 0}, static_cast<double>(i)});
  EXPECT_TRUE(build_light_buffer({0, 0, 0}, nested, 1e3).empty());
  LightBufferLimits limits;
  limits.max_around = 64;
  EXPECT_FALSE(build_light_buffer({0, 0, 0}, nested, 1e3, limits).empty());
}

TEST(LightBuffer, IsUsedAndReportedOnlyWithShadowsAndWhenSpecialized) {
  Rng rng(14);
  Scene scene = random_scene(rng, 300, 4);
  RenderOptions o;
  auto has = [](const PreparedScene<double>& p) {
    auto v = p.features.parts();
    return std::find(v.begin(), v.end(), "light-buffers") != v.end();
  };
  EXPECT_TRUE(has(prepare_scene<double>(scene, o, 0)));
  o.shadows = false;
  EXPECT_FALSE(has(prepare_scene<double>(scene, o, 0)));
  EXPECT_TRUE(prepare_scene<double>(scene, o, 0).light_buffers.empty());
  o.shadows = true;
  o.specialize = false;
  EXPECT_FALSE(has(prepare_scene<double>(scene, o, 0)));
}

TEST(LightBuffer, ManyLightsShareAMemoryBudgetAndTheRestKeepTheHierarchy) {
  Rng rng(15);
  Scene scene = random_scene(rng, 300, 4);
  scene.lights.clear();
  for (int i = 0; i < 40; ++i)
  {
    Light& l = scene.lights.emplace_back();
    l.name = "l" + std::to_string(i);
    l.location = rng.point(12);
    l.emissivity = glm::dvec3(0.05);
  }
  const PreparedScene<double> p = prepare_scene<double>(scene, {}, 0);
  std::size_t built = 0, entries = 0;
  for (const LightBuffer& lb : p.light_buffers) {
    built += !lb.empty();
    entries += lb.entries.size();
  }
  EXPECT_GT(built, 0u);
  EXPECT_LT(built, scene.lights.size());
  // The budget (64 entries a sphere), overshot by one buffer (48 a sphere at most).
  EXPECT_LE(entries, (64 + 48) * scene.count<Sphere>());
  RenderOptions o;
  o.width = 40;
  o.height = 30;
  const Image fast = render_image(scene, o, 2);
  o.specialize = false;
  EXPECT_EQ(render_image(scene, o, 1), fast);
}

// The culling structures are tasks that whichever build thread is free takes (the screen
// bins, each mirror plane's bins, each light's buffer): the same structures however many
// threads build them, the memory budget included (kept in light order until it is spent).
TEST(LightBuffer, CullingStructuresAreTheSameWhateverThreadsBuildThem) {
  Rng rng(16);
  Scene scene = random_scene(rng, 300, 4);
  scene.materials[0].specular = glm::dvec3(0.4);  // the floor sends reflection rays: mirror bins
  scene.lights.clear();
  for (int i = 0; i < 40; ++i) {
    Light& l = scene.lights.emplace_back();
    l.name = "l" + std::to_string(i);
    l.location = rng.point(12);
  }
  const PreparedScene<double> one = prepare_scene<double>(scene, {}, 0, 1);
  ASSERT_TRUE(one.features.screen_bins);
  ASSERT_TRUE(one.features.mirror_bins);
  ASSERT_TRUE(one.features.light_buffers);
  auto same_bins = [](const ScreenBins& a, const ScreenBins& b) {
    auto key = [](const ScreenBinEntry& e) {
      return std::tuple(e.sphere, e.near, e.x0, e.x1, e.r0, e.r1);
    };
    return a.tile == b.tile && a.tiles_x == b.tiles_x && a.tiles_y == b.tiles_y &&
           a.start == b.start &&
           std::equal(a.entries.begin(), a.entries.end(), b.entries.begin(), b.entries.end(),
                      [&](const auto& x, const auto& y) { return key(x) == key(y); });
  };
  // The budget cut in: the buffers kept are the first lights', each but the first
  // begun with no more than 64 entries a sphere spent.
  std::size_t kept = 0;
  double entries = 0;
  for (const LightBuffer& lb : one.light_buffers) {
    if (lb.empty()) break;
    EXPECT_LE(entries, 64.0 * 300);
    entries += static_cast<double>(lb.entries.size());
    ++kept;
  }
  EXPECT_GT(kept, 0u);
  EXPECT_LT(kept, scene.lights.size());
  for (std::size_t i = kept; i < one.light_buffers.size(); ++i)
    EXPECT_TRUE(one.light_buffers[i].empty()) << i;
  for (int threads : {2, 3, 8}) {
    const PreparedScene<double> many = prepare_scene<double>(scene, {}, 0, threads);
    EXPECT_EQ(many.features.parts(), one.features.parts()) << threads;
    EXPECT_TRUE(same_bins(many.screen_bins, one.screen_bins)) << threads;
    ASSERT_EQ(many.mirror_bins.size(), one.mirror_bins.size()) << threads;
    for (std::size_t j = 0; j < one.mirror_bins.size(); ++j)
      EXPECT_TRUE(same_bins(many.mirror_bins[j], one.mirror_bins[j])) << threads << " " << j;
    EXPECT_EQ(many.mirror_reach, one.mirror_reach);
    ASSERT_EQ(many.light_buffers.size(), one.light_buffers.size()) << threads;
    for (std::size_t i = 0; i < one.light_buffers.size(); ++i) {
      const LightBuffer &a = many.light_buffers[i], &b = one.light_buffers[i];
      EXPECT_EQ(a.n, b.n) << threads << " light " << i;
      EXPECT_EQ(a.start, b.start) << threads << " light " << i;
      EXPECT_EQ(a.around, b.around) << threads << " light " << i;
      ASSERT_EQ(a.entries.size(), b.entries.size()) << threads << " light " << i;
      for (std::size_t k = 0; k < a.entries.size(); ++k)
        ASSERT_TRUE(a.entries[k].blocker == b.entries[k].blocker &&
                    a.entries[k].near == b.entries[k].near)
            << threads << " light " << i << " entry " << k;
    }
  }
}

}  // namespace
}  // namespace rayfarm
