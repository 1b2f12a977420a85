// The sphere hierarchy answers exactly as the plain loop does (object and t, to the bit), for
// seeded random scenes and rays, the Origin rule, coincident and touching spheres, extreme
// scales; and it is the same whatever the number of threads that built it.
#include "accel/bvh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <utility>

#include "random_scene.h"
#include "rayfarm/load.h"
#include "rayfarm/render.h"
#include "render/prepared_scene.h"
#include "render/tracer.h"

namespace rayfarm {
namespace {

using test::add_sphere;
using test::base_scene;
using test::random_scene;
using test::Rng;

// The same prepared scene twice: once with a hierarchy, once without (the plain loop).
template <class T>
struct Pair {
  PreparedScene<T> loop;
  PreparedScene<T> bvh;
};

template <class T>
Pair<T> prepare_both(const Scene& scene, int width, int threads = 2) {
  RenderOptions o;
  o.specialize = false;  // never builds the hierarchy
  Pair<T> p{prepare_scene<T>(scene, o, 0), prepare_scene<T>(scene, o, 0)};
  build_sphere_bvh(p.bvh, threads, width);
  return p;
}

// The node widths this processor can walk: 4 always, 8 with AVX2.
std::vector<int> widths() {
  if (bvh_best_width() == 8) return {4, 8};
  return {4};
}

template <class T>
bool same(const Hit<T>& a, const Hit<T>& b) {
  return a.object == b.object && std::memcmp(&a.t, &b.t, sizeof(T)) == 0;
}

// Rays of every kind the tracer makes: from outside the scene, from inside it, and
// secondary rays leaving a hit point (from outside or inside of the object hit), with
// finite and infinite limits; closest and occluded must agree.
template <class T>
void expect_same_answers(const Scene& scene, Rng& rng, double extent, int rays, int width) {
  SCOPED_TRACE("width " + std::to_string(width));
  const Pair<T> p = prepare_both<T>(scene, width);
  ASSERT_FALSE(p.bvh.bvh.empty());
  ASSERT_EQ(width == 8, !p.bvh.bvh.nodes8.empty());
  const Tracer<T> loop(p.loop), bvh(p.bvh);
  const int objects = static_cast<int>(p.loop.spheres.size() + p.loop.planes.size());
  int hits = 0, occluded = 0;
  for (int i = 0; i < rays; ++i) {
    Vec3<T> o(rng.point(rng.chance(0.3) ? 3 * extent : extent));
    Vec3<T> d(rng.direction());
    if (rng.chance(0.05)) d = Vec3<T>(0, 0, rng.chance(0.5) ? -1 : 1);  // axis-parallel
    if (rng.chance(0.02)) d = Vec3<T>(-0.0, 1, 0);
    const T inf = std::numeric_limits<T>::infinity();
    const T t_max = rng.chance(0.5) ? inf : static_cast<T>(rng.in(0, 2 * extent));
    Origin from;
    if (rng.chance(0.3)) from = {rng.below(objects), rng.chance(0.5)};
    Hit<T> a = loop.closest(o, d, from, t_max);
    Hit<T> b = bvh.closest(o, d, from, t_max);
    ASSERT_TRUE(same(a, b)) << "ray " << i << ": loop " << a.object << " t " << a.t << ", bvh "
                            << b.object << " t " << b.t;
    if (a.object < 0) continue;
    ++hits;
    // A secondary ray from the hit point, as the tracer would send it.
    const Vec3<T> hit_point = o + a.t * d;
    const Origin leaving{a.object, rng.chance(0.5)};
    const Vec3<T> d2(rng.direction());
    Hit<T> a2 = loop.closest(hit_point, d2, leaving, inf);
    Hit<T> b2 = bvh.closest(hit_point, d2, leaving, inf);
    ASSERT_TRUE(same(a2, b2)) << "secondary ray " << i << ": loop " << a2.object << " t " << a2.t
                              << ", bvh " << b2.object << " t " << b2.t;
    const T dist = static_cast<T>(rng.in(0, 2 * extent));
    const bool blocked = loop.occluded(hit_point, d2, leaving, dist);
    ASSERT_EQ(blocked, bvh.occluded(hit_point, d2, leaving, dist)) << "shadow ray " << i;
    occluded += blocked;
  }
  // The rays must exercise both answers, or the comparison proves little.
  EXPECT_GT(hits, rays / 20);
  EXPECT_GT(occluded, 0);
}

TEST(Bvh, ClosestAndOccludedEqualTheLoopOnRandomScenes) {
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    Rng rng(seed);
    const int count = std::vector<int>{20, 200, 3000}[seed % 3];
    const Scene scene = random_scene(rng, count, 10);
    for (int width : widths()) {
      expect_same_answers<double>(scene, rng, 10, 4000, width);
      expect_same_answers<float>(scene, rng, 10, 4000, width);
    }
  }
}

TEST(Bvh, EqualsTheLoopAtExtremeScales) {
  for (double scale : {1e-6, 1e6, 1e12}) {
    SCOPED_TRACE("scale " + std::to_string(scale));
    Rng rng(99);
    const Scene scene = random_scene(rng, 500, scale);
    for (int width : widths()) {
      expect_same_answers<double>(scene, rng, scale, 3000, width);
      expect_same_answers<float>(scene, rng, scale, 3000, width);
    }
  }
}

// Rays grazing a sphere where it touches its own box (the point of largest x, y or z): the
// computed hit may lie a rounding error outside the box, which the slab margin must cover.
template <class T>
void expect_same_grazing_answers(double extent, int width) {
  SCOPED_TRACE("width " + std::to_string(width));
  Rng rng(11);
  Scene scene = base_scene();
  for (int i = 0; i < 300; ++i) add_sphere(scene, rng.point(extent), extent * rng.in(0.001, 0.05));
  const Pair<T> p = prepare_both<T>(scene, width);
  const Tracer<T> loop(p.loop), bvh(p.bvh);
  int hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const Sphere& sp = test::sphere_at(scene, rng.below(300));
    const int axis = rng.below(3);
    glm::dvec3 normal(0);
    normal[axis] = rng.chance(0.5) ? 1 : -1;
    const glm::dvec3 touch = sp.center + sp.radius * normal;
    // A direction in the tangent plane, tilted by a hair towards or away from the sphere.
    glm::dvec3 d = rng.direction();
    d -= glm::dot(d, normal) * normal;
    d = glm::normalize(glm::normalize(d) + rng.in(-1e-6, 1e-6) * normal);
    const glm::dvec3 o = touch - rng.in(0.01, 3) * extent * d;
    Hit<T> a = loop.closest(Vec3<T>(o), Vec3<T>(d), {}, std::numeric_limits<T>::infinity());
    Hit<T> b = bvh.closest(Vec3<T>(o), Vec3<T>(d), {}, std::numeric_limits<T>::infinity());
    ASSERT_TRUE(same(a, b)) << "ray " << i << ": loop " << a.object << ", bvh " << b.object;
    ASSERT_EQ(loop.occluded(Vec3<T>(o), Vec3<T>(d), {}, T(4 * extent)),
              bvh.occluded(Vec3<T>(o), Vec3<T>(d), {}, T(4 * extent)))
        << "ray " << i;
    hits += a.object >= 0;
  }
  EXPECT_GT(hits, 1000);
}

TEST(Bvh, GrazingRaysAtTheBoxFacesEqualTheLoop) {
  for (double extent : {1.0, 1e-5, 1e5}) {
    SCOPED_TRACE("extent " + std::to_string(extent));
    for (int width : widths()) {
      expect_same_grazing_answers<double>(extent, width);
      expect_same_grazing_answers<float>(extent, width);
    }
  }
}

TEST(Bvh, CoincidentSpheresResolveToTheLowestIndex) {
  Scene s = base_scene();
  // Sixteen identical spheres, then more spheres around them, then sixteen more copies.
  for (int i = 0; i < 16; ++i) add_sphere(s, {0, 0, -5}, 1);
  Rng rng(5);
  for (int i = 0; i < 100; ++i)
    add_sphere(s, glm::dvec3(3 + rng.in(0, 5), 0, 0) + rng.point(3), 0.3);
  for (int i = 0; i < 16; ++i) add_sphere(s, {0, 0, -5}, 1);
  for (int width : widths()) {
    SCOPED_TRACE("width " + std::to_string(width));
    const Pair<double> p = prepare_both<double>(s, width);
    const Tracer<double> loop(p.loop), bvh(p.bvh);
    const glm::dvec3 o(0, 0, 5);
    Hit<double> a = loop.closest(o, {0, 0, -1}, {}, 1e300);
    Hit<double> b = bvh.closest(o, {0, 0, -1}, {}, 1e300);
    EXPECT_EQ(a.object, 0);
    EXPECT_TRUE(same(a, b));
    // Leaving twin 3 from outside: it is skipped, twin 0 (same t) is not.
    const glm::dvec3 surface(0, 0, -4);
    a = loop.closest(surface, {0, 0, 1}, {3, false}, 1e300);
    b = bvh.closest(surface, {0, 0, 1}, {3, false}, 1e300);
    EXPECT_TRUE(same(a, b));
    for (int k = 0; k < 200; ++k) {
      const glm::dvec3 d = rng.direction();
      const Origin from{rng.below(32) < 16 ? rng.below(16) : 116 + rng.below(16), rng.chance(0.5)};
      a = loop.closest(surface, d, from, 1e300);
      b = bvh.closest(surface, d, from, 1e300);
      ASSERT_TRUE(same(a, b)) << k;
      ASSERT_EQ(loop.occluded(surface, d, from, 3.0), bvh.occluded(surface, d, from, 3.0)) << k;
    }
  }
}

TEST(Bvh, TouchingSpheresAgreeWithTheLoopAtTheContactPoint) {
  Scene s = base_scene();
  // A row of spheres, each touching the next, and a cluster around the contacts.
  for (int i = 0; i < 40; ++i) add_sphere(s, {2.0 * i, 0, -5}, 1);
  Rng rng(8);
  for (int i = 0; i < 60; ++i) add_sphere(s, {rng.in(0, 80), rng.in(-3, 3), rng.in(-8, -2)}, 0.25);
  for (int width : widths()) {
    SCOPED_TRACE("width " + std::to_string(width));
    const Pair<double> p = prepare_both<double>(s, width);
    const Tracer<double> loop(p.loop), bvh(p.bvh);
    for (int i = 0; i + 1 < 40; ++i) {
      const glm::dvec3 contact(2.0 * i + 1, 0, -5);
      for (int k = 0; k < 50; ++k) {
        const glm::dvec3 d = rng.direction();
        for (Origin from :
             {Origin{i, false}, Origin{i, true}, Origin{i + 1, false}, Origin{i + 1, true}}) {
          Hit<double> a = loop.closest(contact, d, from, 1e300);
          Hit<double> b = bvh.closest(contact, d, from, 1e300);
          ASSERT_TRUE(same(a, b)) << "contact " << i << " ray " << k;
          ASSERT_EQ(loop.occluded(contact, d, from, 10.0), bvh.occluded(contact, d, from, 10.0));
        }
      }
    }
  }
}

// The spheres' bounding boxes, as scene preparation gives them to the builder.
std::vector<BvhBox> boxes_of(const Scene& scene) {
  std::vector<BvhBox> boxes;
  for (const Object& o : scene.objects)
    if (const Sphere* sp = o.as<Sphere>())
      boxes.push_back({sp->center - sp->radius, sp->center + sp->radius});
  return boxes;
}

template <int W>
const std::vector<BvhNodeOf<W>>& nodes_of(const Bvh& bvh) {
  if constexpr (W == 8)
    return bvh.nodes8;
  else
    return bvh.nodes;
}

TEST(Bvh, BuildIsTheSameForAnyThreadCount) {
  Rng rng(3);
  const Scene scene = random_scene(rng, 40000, 50);
  const std::vector<BvhBox> boxes = boxes_of(scene);
  auto check = [&]<int W>() {
    SCOPED_TRACE("width " + std::to_string(W));
    const Bvh one = build_bvh(boxes, {1, 4, W});
    ASSERT_FALSE(one.empty());
    ASSERT_FALSE(nodes_of<W>(one).empty());
    for (int threads : {2, 3, 8}) {
      const Bvh many = build_bvh(boxes, {threads, 4, W});
      ASSERT_EQ(one.order, many.order) << threads;
      ASSERT_EQ(nodes_of<W>(one).size(), nodes_of<W>(many).size()) << threads;
      EXPECT_EQ(std::memcmp(nodes_of<W>(one).data(), nodes_of<W>(many).data(),
                            nodes_of<W>(one).size() * sizeof(BvhNodeOf<W>)),
                0)
          << threads;
    }
  };
  check.operator()<4>();
  check.operator()<8>();  // built on any processor; only walked where AVX2 is
}

// Every primitive once, in a leaf whose box holds its box; returns the leaves' (first, count)
// in the order a depth-first walk meets them.
template <int W>
std::vector<std::pair<int, int>> check_leaves(const Bvh& bvh, const std::vector<BvhBox>& boxes) {
  std::vector<std::pair<int, int>> leaves;
  std::vector<int> seen(boxes.size(), 0);
  std::vector<std::int32_t> stack{0};
  while (!stack.empty()) {
    const BvhNodeOf<W>& n = nodes_of<W>(bvh)[stack.back()];
    stack.pop_back();
    for (int i = 0; i < W; ++i) {
      if (n.count[i] < 0) continue;
      if (n.count[i] == 0) {
        stack.push_back(n.child[i]);
        continue;
      }
      leaves.emplace_back(n.child[i], n.count[i]);
      for (int k = n.child[i]; k < n.child[i] + n.count[i]; ++k) {
        const BvhBox& b = boxes[bvh.order[k]];
        ++seen[bvh.order[k]];
        for (int a = 0; a < 3; ++a) {
          EXPECT_LE(n.box[a][i], b.lo[a]);
          EXPECT_GE(n.box[3 + a][i], b.hi[a]);
        }
      }
    }
  }
  for (std::size_t i = 0; i < seen.size(); ++i) EXPECT_EQ(seen[i], 1) << i;
  std::sort(leaves.begin(), leaves.end());
  return leaves;
}

TEST(Bvh, EveryPrimitiveIsInExactlyOneLeafInsideItsNodeBox) {
  Rng rng(4);
  const Scene scene = random_scene(rng, 5000, 20);
  const std::vector<BvhBox> boxes = boxes_of(scene);
  const Bvh four = build_bvh(boxes, {2, 4, 4});
  const Bvh eight = build_bvh(boxes, {2, 4, 8});
  // Both widths collapse the same binary tree: the same leaves over the same order, the
  // eight-wide tree in fewer, fuller nodes.
  EXPECT_EQ(four.order, eight.order);
  EXPECT_EQ(check_leaves<4>(four, boxes), check_leaves<8>(eight, boxes));
  EXPECT_EQ(four.stats.leaves, eight.stats.leaves);
  EXPECT_LT(eight.nodes8.size() * 3, four.nodes.size() * 2);
}

// Leaves merged when collapsing, at either width: each primitive still in exactly one leaf
// inside its box, each merged leaf a run of the plain tree's leaves over cheap primitives
// only, at most merge_max of them; fewer nodes.
template <int W>
void check_merged(const std::vector<BvhBox>& boxes, std::size_t cheap) {
  BvhBuildOptions plain{2, 4, W};
  BvhBuildOptions merging = plain;
  merging.merge_max = 8;
  merging.merge_below = cheap;
  const Bvh a = build_bvh(boxes, plain), b = build_bvh(boxes, merging);
  ASSERT_EQ(a.order, b.order);  // one binary tree, collapsed two ways
  const auto plain_leaves = check_leaves<W>(a, boxes), merged_leaves = check_leaves<W>(b, boxes);
  std::map<int, int> plain_at(plain_leaves.begin(), plain_leaves.end());
  int merged = 0;
  for (const auto& [first, count] : merged_leaves) {
    if (plain_at.count(first) && plain_at[first] == count) continue;
    ++merged;
    EXPECT_LE(count, 8);
    int k = first;  // whole plain leaves, end to end
    while (k < first + count) {
      ASSERT_TRUE(plain_at.count(k)) << "a merged leaf cuts a leaf at " << k;
      k += plain_at[k];
    }
    EXPECT_EQ(k, first + count);
    for (int i = first; i < first + count; ++i)
      EXPECT_LT(static_cast<std::size_t>(b.order[i]), cheap) << "a dear primitive merged";
  }
  EXPECT_GT(merged, 0);
  EXPECT_LT(nodes_of<W>(b).size(), nodes_of<W>(a).size());
}

TEST(Bvh, SmallSubtreesOfCheapPrimitivesBecomeOneLeaf) {
  Rng rng(4);
  const Scene scene = random_scene(rng, 5000, 20);
  const std::vector<BvhBox> boxes = boxes_of(scene);
  check_merged<4>(boxes, boxes.size() - 500);  // the last 500 stand for dearer shapes
  check_merged<8>(boxes, boxes.size() - 500);
}

// Merging is priced: eight boxes that overlap are cheaper as one leaf than behind a node,
// eight specks spread over a wide box are not (a ray meeting the wide box meets few).
TEST(Bvh, MergesTightGroupsAndKeepsSparseOnesApart) {
  std::vector<BvhBox> boxes;
  std::vector<bool> tight;
  for (int g = 0; g < 64; ++g) {
    const glm::dvec3 at(100.0 * (g % 8), 100.0 * (g / 8), 0);
    for (int i = 0; i < 8; ++i) {
      const glm::dvec3 jitter(0.01 * i, 0.013 * (i % 3), 0.007 * (i % 5));
      if (g % 2 == 0) {
        boxes.push_back({at + jitter - 1.0, at + jitter + 1.0});
      } else {
        const glm::dvec3 c = at + 10.0 * glm::dvec3(i & 1, (i >> 1) & 1, (i >> 2) & 1);
        boxes.push_back({c - 0.01, c + 0.01});
      }
      tight.push_back(g % 2 == 0);
    }
  }
  BvhBuildOptions merging{1, 4, 8};
  merging.merge_max = 8;
  const Bvh b = build_bvh(boxes, merging);
  int tight_in_big = 0, tight_total = 0;
  for (const auto& [first, count] : check_leaves<8>(b, boxes)) {
    for (int i = first; i < first + count; ++i) {
      if (tight[b.order[i]]) {
        ++tight_total;
        tight_in_big += count > 4;
      } else {
        EXPECT_LE(count, 4) << "specks far apart merged past the price of a node";
      }
    }
  }
  EXPECT_EQ(tight_total, 64 * 4);
  EXPECT_GT(tight_in_big, tight_total / 2);
}

TEST(Bvh, DepthStaysBoundedOnDegenerateInput) {
  // Spheres at exponentially growing distances: SAH alone would peel one off per level.
  std::vector<BvhBox> boxes;
  for (int i = 0; i < 3000; ++i) {
    const double x = std::pow(1.01, i);
    boxes.push_back({{x - 0.01, -0.01, -0.01}, {x + 0.01, 0.01, 0.01}});
  }
  const Bvh bvh = build_bvh(boxes, {1, 4});
  ASSERT_FALSE(bvh.empty());
  EXPECT_LT(bvh.stats.depth, kBvhMaxDepth);
}

TEST(Bvh, OutOfRangeCoordinatesKeepThePlainLoop) {
  std::vector<BvhBox> boxes{{{0, 0, 0}, {1, 1, 1}}, {{1e30, 0, 0}, {1e30 + 1e15, 1, 1}}};
  EXPECT_TRUE(build_bvh(boxes).empty());
}

TEST(Bvh, IsUsedAndReportedOnlyAboveTheThresholdAndWhenSpecialized) {
  Rng rng(6);
  RenderOptions o;
  const Scene few = random_scene(rng, static_cast<int>(kBvhMinSpheres) - 1, 5);
  const Scene many = random_scene(rng, 500, 5);
  auto parts = [](const PreparedScene<double>& p) { return p.features.parts(); };
  auto has_bvh = [&](const PreparedScene<double>& p) {
    auto v = parts(p);
    return std::find(v.begin(), v.end(), "bvh") != v.end();
  };
  EXPECT_FALSE(has_bvh(prepare_scene<double>(few, o, 0)));
  EXPECT_TRUE(prepare_scene<double>(few, o, 0).bvh.empty());
  EXPECT_TRUE(has_bvh(prepare_scene<double>(many, o, 0)));
  o.specialize = false;
  EXPECT_FALSE(has_bvh(prepare_scene<double>(many, o, 0)));
  EXPECT_TRUE(prepare_scene<double>(many, o, 0).bvh.empty());
}

TEST(Bvh, RenderIsByteIdenticalWithAndWithoutTheHierarchyForAnyThreadCount) {
  Rng rng(7);
  Scene scene = random_scene(rng, 2000, 4);
  scene.materials[0].specular = glm::dvec3(0.5);  // reflections and highlights too
  scene.cameras[0].viewpoint = {0, 0, 12};
  scene.cameras[0].world_width = 8;
  for (Precision precision : {Precision::f64, Precision::f32}) {
    RenderOptions o;
    o.width = 96;
    o.height = 72;
    o.precision = precision;
    RenderStats stats;
    const Image with = render_image(scene, o, 3, &stats);
    ASSERT_NE(std::find(stats.parts.begin(), stats.parts.end(), "bvh"), stats.parts.end());
    EXPECT_EQ(render_image(scene, o, 1), with);
    o.specialize = false;
    EXPECT_EQ(render_image(scene, o, 2), with);
  }
}

}  // namespace
}  // namespace rayfarm
