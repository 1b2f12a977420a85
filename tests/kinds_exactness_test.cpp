// Every kind of object and light against the plain loops: seeded random scenes with spheres,
// planes, tiled planes (both forms), fplanes, texplanes, triangles, tris and revsurfs, lit by
// point lights, spotlights and projectors, with reflective and translucent materials. With
// the scene-specific pipeline (hierarchies, screen and mirror bins, light buffers) and without
// it (a plain loop everywhere) a render gives the same bytes, and the tracer's closest,
// occluded and transmittance give the same answers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>

#include "random_scene.h"
#include "rayfarm/render.h"
#include "render/lecture_pipeline.h"
#include "render/prepared_scene.h"
#include "render/tracer.h"
#include "test_util.h"

namespace rayfarm {
namespace {

using test::Rng;

// The scene's objects lie in this box, in front of the screen z = 0 and behind it.
const glm::dvec3 kLo{-1, -1, -11}, kHi{9, 7, 1};

glm::dvec3 point_in_box(Rng& rng) {
  return {rng.in(kLo.x, kHi.x), rng.in(kLo.y, kHi.y), rng.in(kLo.z, kHi.z)};
}

// Half the time along an axis: flat shapes parallel to the axes have flat boxes, where the
// hierarchy's slab test is tightest.
glm::dvec3 random_normal(Rng& rng) {
  if (rng.chance(0.5)) {
    glm::dvec3 n(0);
    n[rng.below(3)] = rng.chance(0.5) ? 1 : -1;
    return n;
  }
  return rng.direction();
}

// A direction not parallel to n (an xdir with a part in the plane).
glm::dvec3 random_xdir(Rng& rng, const glm::dvec3& n) {
  for (;;) {
    const glm::dvec3 x = rng.chance(0.3) ? glm::dvec3(1, 0, 0) : rng.direction();
    if (glm::length(x - glm::dot(x, n) * n) > 0.2) return x;
  }
}

Material material(std::string name, glm::dvec3 ambient, glm::dvec3 diffuse, glm::dvec3 specular,
                  std::optional<double> shininess = std::nullopt, double transparency = 0) {
  Material m;
  m.name = std::move(name);
  m.ambient = ambient;
  m.diffuse = diffuse;
  m.specular = specular;
  m.shininess = shininess;
  m.transparency = transparency;
  return m;
}

void add(Scene& s, EntityKind kind, int material, Shape shape) {
  Object& o = s.objects.emplace_back();
  o.name = "o" + std::to_string(s.objects.size());
  o.kind = kind;
  o.material = material;
  o.shape = std::move(shape);
}

// A small image of random texels.
std::shared_ptr<const Image> random_image(Rng& rng, int w, int h) {
  Image img(w, h);
  for (auto& b : img.rgb) b = static_cast<std::uint8_t>(rng.below(256));
  return std::make_shared<const Image>(std::move(img));
}

// Objects of every kind, in file order mixed. `translucent` adds glass materials (which turn
// the light buffers off: shadow rays must then find every object on their way).
Scene kinds_scene(Rng& rng, bool translucent) {
  Scene s;
  Camera cam;
  cam.name = "c";
  cam.width = 36;
  cam.height = 27;
  cam.world_width = 8;
  cam.world_height = 6;
  cam.viewpoint = {4, 3, 5};
  s.cameras.push_back(cam);

  s.materials.push_back(material("matte", glm::dvec3(1.5), {0.7, 0.5, 0.3}, glm::dvec3(0)));
  s.materials.push_back(material("mirror", glm::dvec3(0.8), glm::dvec3(0.3), glm::dvec3(0.5), 16));
  s.materials.push_back(material("glow", glm::dvec3(3, 2, 1), glm::dvec3(0), glm::dvec3(0)));
  s.materials.push_back(material("alt", {2, 0.4, 0.4}, {0.2, 0.7, 0.2}, glm::dvec3(0)));
  s.materials.push_back(material("shiny", glm::dvec3(1), glm::dvec3(0.4), {0.2, 0.3, 0.4}));
  if (translucent) {
    s.materials.push_back(
        material("glass", glm::dvec3(0.5), {0.9, 0.6, 0.3}, glm::dvec3(0), std::nullopt, 0.6));
    s.materials.push_back(
        material("glassy mirror", glm::dvec3(0.5), {0.3, 0.8, 0.8}, glm::dvec3(0.3), 8, 0.4));
  }
  const int n_materials = static_cast<int>(s.materials.size());
  auto any_material = [&] { return rng.below(n_materials); };

  Texture tex;
  tex.name = "t";
  tex.path = "t.ppm";
  tex.image = random_image(rng, 5, 4);
  s.textures.push_back(tex);

  Light point;
  point.name = "point";
  point.location = {rng.in(0, 8), rng.in(4, 9), rng.in(-6, 3)};
  point.emissivity = glm::dvec3(rng.in(2, 6));
  s.lights.push_back(point);
  Light spot;
  spot.name = "spot";
  spot.kind = LightKind::spot;
  spot.location = {rng.in(-2, 10), rng.in(5, 9), rng.in(-4, 2)};
  spot.emissivity = {5, 4, 3};
  spot.aim = point_in_box(rng);
  spot.theta = rng.in(15, 40);
  s.lights.push_back(spot);
  Light projector;
  projector.name = "projector";
  projector.kind = LightKind::projector;
  projector.location = {rng.in(2, 6), rng.in(3, 6), rng.in(1, 4)};
  projector.emissivity = glm::dvec3(6);
  projector.normal = {0, 0, 1};
  projector.point = projector.location + glm::dvec3(-1.5, -1.5, -1);
  projector.window = {{1, 0, 0}, 3, 3};
  projector.texture = 0;
  s.lights.push_back(projector);

  // Spheres first and a mirror wall on the left, then the other kinds shuffled.
  for (int i = 0; i < 10; ++i)
    add(s, EntityKind::sphere, any_material(), Sphere{point_in_box(rng), rng.in(0.2, 1)});
  add(s, EntityKind::plane, 1, Plane{{1, 0, 0}, {-2, 0, 0}});  // a mirror: mirror bins
  std::vector<int> kinds;
  for (int i = 0; i < 3; ++i) kinds.push_back(0);  // fplane
  for (int i = 0; i < 2; ++i) kinds.push_back(1);  // texplane
  for (int i = 0; i < 2; ++i) kinds.push_back(2);  // triangle
  for (int i = 0; i < 2; ++i) kinds.push_back(3);  // tri
  kinds.push_back(4);                              // revsurf, a cone
  kinds.push_back(7);                              // revsurf, a wave
  kinds.push_back(5);                              // tiled_plane: the back wall
  kinds.push_back(6);                              // tiled_plane, 2009 form: the floor
  std::shuffle(kinds.begin(), kinds.end(), rng.engine);
  for (int kind : kinds) {
    const glm::dvec3 n = random_normal(rng), p = point_in_box(rng);
    switch (kind) {
      case 0:
        add(s, EntityKind::fplane, any_material(),
            FinitePlane{{n, p}, {random_xdir(rng, n), rng.in(0.5, 3), rng.in(0.5, 3)}});
        break;
      case 1:
        add(s, EntityKind::texplane, any_material(),
            TexPlane{{n, p}, {random_xdir(rng, n), rng.in(1, 4), rng.in(1, 4)}, 0, rng.below(2)});
        break;
      case 2: {
        // Vertices off the plane, as the course's triangles may have them.
        Triangle t;
        for (glm::dvec3& v : t.vertex) v = p + rng.point(2);
        t.plane = Plane{n, p};
        add(s, EntityKind::triangle, any_material(), t);
        break;
      }
      case 3: {
        Triangle t;
        for (glm::dvec3& v : t.vertex) v = p + rng.point(2);
        add(s, EntityKind::tri, any_material(), t);
        break;
      }
      case 4:
      case 7:
        // Short: every ray through a surface's cylinder costs a root search in the loop.
        add(s, EntityKind::revsurf, any_material(),
            Revsurf{kind == 4 ? 1 : 2 + rng.below(2), p, rng.direction(), rng.in(0.5, 2)});
        break;
      case 5:
        add(s, EntityKind::tiled_plane, any_material(),
            TiledPlane{{{0, 0, 1}, {0, 0, -12}},
                       {random_xdir(rng, {0, 0, 1}), rng.in(0.5, 2), rng.in(0.5, 2)},
                       false,
                       3});
        break;
      default:
        add(s, EntityKind::tiled_plane, any_material(),
            TiledPlane{
                {{0, 1, 0}, {0, -1.5, 0}}, {{1, 0, 0}, rng.in(0.5, 2), rng.in(0.5, 2)}, true, 3});
        break;
    }
  }
  // Exact copies of the first fplane and triangle in another material: at equal t the lower
  // object number wins, in the loops and in the hierarchy alike.
  for (EntityKind kind : {EntityKind::fplane, EntityKind::triangle}) {
    const auto original = std::find_if(s.objects.begin(), s.objects.end(),
                                       [&](const Object& o) { return o.kind == kind; });
    add(s, kind, (original->material + 1) % n_materials, original->shape);
  }
  // A far wall and a panel on it, the same plane: where the panel is, the wall wins (a plane
  // has a lower number than any other shape), whatever structure finds the two.
  const Plane wall{{0, 0, 1}, {-30, -20, -30}};
  add(s, EntityKind::plane, 0, wall);
  add(s, EntityKind::fplane, 3, FinitePlane{wall, Window{{1, 0, 0}, 60, 40}});
  return s;
}

// Eyes in front of the scene, high to one side, far away, and among the objects.
const glm::dvec3 kEyes[] = {{4, 3, 5}, {0, 8, 6}, {4, 3, 30}, {4, 3, -5}};

std::string seed_and_eye(std::uint64_t seed, const glm::dvec3& eye) {
  return "seed " + std::to_string(seed) + " eye " + std::to_string(eye.x) + "," +
         std::to_string(eye.y) + "," + std::to_string(eye.z);
}

TEST(KindsExactness, RandomScenesOfEveryKindRenderTheSameWithAndWithoutSpecialization) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    Rng rng(seed);
    const bool translucent = seed % 2 == 1;
    Scene scene = kinds_scene(rng, translucent);
    ASSERT_FALSE(prepare_scene<double>(scene, RenderOptions{}, 0, 2).shape_bvh.empty());
    for (const glm::dvec3& eye : kEyes) {
      scene.cameras[0].viewpoint = eye;
      for (Precision precision : {Precision::f64, Precision::f32})
        for (int spp : {1, 4}) {
          SCOPED_TRACE(seed_and_eye(seed, eye) + " " + std::string(to_string(precision)) + " spp " +
                       std::to_string(spp));
          RenderOptions o;
          o.precision = precision;
          o.spp = spp;
          // The camera's window at fewer pixels: the plain loops are slow.
          o.width = spp == 1 ? 20 : 12;
          o.height = spp == 1 ? 15 : 9;
          RenderStats stats;
          const Image fast = render_image(scene, o, 2, &stats);
          ASSERT_EQ(fast.width, o.width);
          for (const char* part : {"bvh", "screen-bins", "mirror-bins"})
            EXPECT_NE(std::find(stats.parts.begin(), stats.parts.end(), part), stats.parts.end())
                << part;
          EXPECT_EQ(std::find(stats.parts.begin(), stats.parts.end(), "light-buffers") !=
                        stats.parts.end(),
                    !translucent);
          o.specialize = false;
          const Image plain = render_image(scene, o, 2);
          ASSERT_EQ(plain.rgb.size(), fast.rgb.size());
          int differ = 0, first = -1;
          for (size_t i = 0; i < fast.rgb.size(); ++i)
            if (fast.rgb[i] != plain.rgb[i]) {
              if (first < 0) first = static_cast<int>(i);
              ++differ;
            }
          EXPECT_EQ(differ, 0) << "first at pixel " << first / 3 % o.width << ","
                               << first / 3 / o.width;
        }
    }
  }
}

template <class T>
bool same(const Hit<T>& a, const Hit<T>& b) {
  return a.object == b.object && std::memcmp(&a.t, &b.t, sizeof(T)) == 0;
}

// Rays from around and inside the scene, and secondary rays leaving the hit points (from
// either side of the object hit), with finite and infinite limits.
// `shared`: whether the shapes share the spheres' hierarchy (else they fit no float nodes).
template <class T>
void expect_same_answers(const Scene& scene, Rng& rng, int rays, bool shared = true) {
  RenderOptions off;
  off.specialize = false;
  const PreparedScene<T> loop = prepare_scene<T>(scene, off, 0);
  const PreparedScene<T> fast = prepare_scene<T>(scene, RenderOptions{}, 0, 2);
  ASSERT_TRUE(loop.bvh.empty());
  ASSERT_TRUE(loop.shape_bvh.empty());
  ASSERT_FALSE(fast.bvh.empty());
  ASSERT_EQ(fast.bvh_shapes, shared) << "the shapes must be in the spheres' hierarchy";
  if (shared) {
    ASSERT_FALSE(fast.shape_bvh.empty()) << "the shapes must be behind their own hierarchy too";
  }
  ASSERT_GE(fast.shapes.size(), 8u);
  const Tracer<T> a(loop), b(fast);
  const int objects =
      static_cast<int>(loop.spheres.size() + loop.planes.size() + loop.shapes.size());
  const glm::dvec3 mid = (kLo + kHi) / 2.0;
  int hits = 0, shape_hits = 0, blocked = 0, blocker_shapes = 0;
  int last_blocker = -1;
  for (int i = 0; i < rays; ++i) {
    const Vec3<T> o(mid + rng.point(rng.chance(0.3) ? 20 : 7));
    Vec3<T> d(rng.direction());
    if (rng.chance(0.05)) d = Vec3<T>(0, 0, rng.chance(0.5) ? -1 : 1);
    if (rng.chance(0.05)) d = Vec3<T>(0, rng.chance(0.5) ? -1 : 1, 0);
    const T inf = std::numeric_limits<T>::infinity();
    const T t_max = rng.chance(0.5) ? inf : static_cast<T>(rng.in(0, 25));
    Origin from;
    if (rng.chance(0.3)) from = {rng.below(objects), rng.chance(0.5)};
    const Hit<T> h1 = a.closest(o, d, from, t_max), h2 = b.closest(o, d, from, t_max);
    ASSERT_TRUE(same(h1, h2)) << "ray " << i << ": loop " << h1.object << " t " << h1.t
                              << ", hierarchy " << h2.object << " t " << h2.t;
    if (h1.object < 0) continue;
    ++hits;
    shape_hits += h1.object >= fast.shape_base();
    const Vec3<T> p = o + h1.t * d;
    const Origin leaving{h1.object, rng.chance(0.5)};
    const Vec3<T> d2(rng.direction());
    const Hit<T> s1 = a.closest(p, d2, leaving, inf), s2 = b.closest(p, d2, leaving, inf);
    ASSERT_TRUE(same(s1, s2)) << "secondary ray " << i << ": loop " << s1.object << " t " << s1.t
                              << ", hierarchy " << s2.object << " t " << s2.t;
    const T dist = static_cast<T>(rng.in(0, 20));
    const bool o1 = a.occluded(p, d2, leaving, dist);
    ASSERT_EQ(o1, b.occluded(p, d2, leaving, dist)) << "shadow ray " << i;
    // With the last blocker carried from ray to ray, as a render does for each light: often
    // a shape or sphere that does not block this ray.
    ASSERT_EQ(o1, b.occluded(p, d2, leaving, dist, &last_blocker)) << "shadow ray " << i;
    blocked += o1;
    blocker_shapes += o1 && last_blocker >= fast.shape_base();
    const Vec3<T> f1 = a.transmittance(p, d2, leaving, dist),
                  f2 = b.transmittance(p, d2, leaving, dist);
    ASSERT_EQ(std::memcmp(&f1, &f2, sizeof f1), 0) << "transmittance " << i;
  }
  // The rays must reach every answer, or the comparison proves little.
  EXPECT_GT(hits, rays / 10);
  EXPECT_GT(shape_hits, rays / 50);
  EXPECT_GT(blocked, rays / 50);
  EXPECT_GT(blocker_shapes, rays / 200) << "shapes must be remembered as blockers too";
}

TEST(KindsExactness, ClosestOccludedAndTransmittanceEqualTheLoopsOnRandomScenes) {
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    Rng rng(100 + seed);
    const Scene scene = kinds_scene(rng, seed % 2 == 0);
    expect_same_answers<double>(scene, rng, 3000);
    expect_same_answers<float>(scene, rng, 3000);
  }
}

// A shape whose box no float node can hold (a triangle 1e20 away) leaves the spheres a
// hierarchy of their own, and the shapes their loop: the same answers again.
TEST(KindsExactness, ShapesBeyondTheNodesLeaveTheSpheresAHierarchyOfTheirOwn) {
  for (std::uint64_t seed = 1; seed <= 2; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    Rng rng(200 + seed);
    Scene scene = kinds_scene(rng, seed % 2 == 0);
    Triangle far;
    far.vertex = {glm::dvec3(1e20, 0, 0), glm::dvec3(1e20, 1, 0), glm::dvec3(1e20, 0, 1)};
    add(scene, EntityKind::triangle, 0, far);
    expect_same_answers<double>(scene, rng, 2000, false);
    expect_same_answers<float>(scene, rng, 2000, false);
  }
}

// Shadow rays that the light buffers answer (they list the other shapes, by the spheres about
// their boxes, after the spheres) are answered as by the loop: from points on every kind,
// from either side, to a point light, a spotlight, a projector and a light inside a surface
// of revolution (whose sphere is then "around" the light), among many small triangles.
template <class T>
void expect_same_buffered_shadows(const Scene& scene, Rng& rng, int rays, int& answered,
                                  int& by_shapes, int& blocked, int& total) {
  RenderOptions off;
  off.specialize = false;
  const PreparedScene<T> loop = prepare_scene<T>(scene, off, 0);
  const PreparedScene<T> fast = prepare_scene<T>(scene, RenderOptions{}, 0, 2);
  ASSERT_TRUE(fast.features.light_buffers);
  ASSERT_EQ(fast.light_buffers.size(), fast.lights.size());
  // The buffers name what the hierarchy holds by its place there (the spheres, and the
  // shapes where it holds them too).
  ASSERT_TRUE(fast.blockers_in_leaf_order);
  // The same buffers numbered as they were built: the same answers, and the same blocker
  // remembered (the first in the cell's order).
  PreparedScene<T> built = fast;
  const auto as_built = [&](std::int32_t& i) {
    if (static_cast<std::size_t>(i) < built.bvh.order.size()) i = built.bvh.order[i];
  };
  for (LightBuffer& lb : built.light_buffers) {
    for (LightBufferEntry& e : lb.entries) as_built(e.blocker);
    for (std::int32_t& i : lb.around) as_built(i);
  }
  built.blockers_in_leaf_order = false;
  const Tracer<T> a(loop), b(fast), c(built);
  const glm::dvec3 mid = (kLo + kHi) / 2.0;
  const T inf = std::numeric_limits<T>::infinity();
  for (int i = 0; i < rays; ++i) {
    const Vec3<T> o(mid + rng.point(rng.chance(0.3) ? 20 : 7));
    const Vec3<T> d(rng.direction());
    const Hit<T> h = a.closest(o, d, {}, inf);
    if (h.object < 0) continue;
    const Vec3<T> p = o + h.t * d;
    const Origin from{h.object, rng.chance(0.5)};
    for (std::size_t l = 0; l < fast.lights.size(); ++l) {
      Vec3<T> to = fast.lights[l].location - p;
      const T r = glm::length(to);
      if (!(r > 0)) continue;
      to /= r;
      const T dist = r * (1 - 64 * std::numeric_limits<T>::epsilon());
      const LightBuffer& buffer = fast.light_buffers[l];
      int blocker = -1;
      const bool expected = a.occluded(p, to, from, dist);
      ASSERT_EQ(b.occluded(p, to, from, dist, &blocker, buffer.empty() ? nullptr : &buffer),
                expected)
          << "ray " << i << " light " << l << " from object " << h.object;
      int built_blocker = -1;
      const LightBuffer& unplaced = built.light_buffers[l];
      ASSERT_EQ(c.occluded(p, to, from, dist, &built_blocker,
                           unplaced.empty() ? nullptr : &unplaced),
                expected);
      ASSERT_EQ(blocker, built_blocker) << "ray " << i << " light " << l;
      LightBuffer::Cell cell;
      answered += !buffer.empty() && buffer.lookup(glm::dvec3(p), cell);
      by_shapes += expected && blocker >= fast.shape_base();
      blocked += expected;
      ++total;
    }
  }
}

TEST(KindsExactness, LightBuffersListingShapesCastTheLoopsShadows) {
  int answered = 0, by_shapes = 0, blocked = 0, total = 0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    Rng rng(500 + seed);
    Scene scene = kinds_scene(rng, false);
    for (int i = 0; i < 150; ++i) {
      Triangle t;
      const glm::dvec3 at = point_in_box(rng);
      for (glm::dvec3& v : t.vertex) v = at + rng.point(0.4);
      add(scene, rng.chance(0.5) ? EntityKind::tri : EntityKind::triangle, 0, t);
    }
    for (const Object& o : scene.objects)
      if (const auto* boxed = std::get_if<Boxed<Revsurf>>(&o.shape)) {
        const Revsurf* r = boxed->get();
        Light& inside = scene.lights.emplace_back();
        inside.name = "inside";
        inside.location = r->base + 0.4 * r->height * glm::normalize(r->direction);
        inside.emissivity = glm::dvec3(3);
        break;
      }
    expect_same_buffered_shadows<double>(scene, rng, 1500, answered, by_shapes, blocked, total);
    expect_same_buffered_shadows<float>(scene, rng, 1500, answered, by_shapes, blocked, total);
  }
  // Both answers, shapes among the blockers, and the buffers (not the fallback) answering.
  EXPECT_GT(blocked, total / 10);
  EXPECT_LT(blocked, total - total / 10);
  EXPECT_GT(by_shapes, blocked / 5);
  EXPECT_GT(answered, total * 3 / 4);
}

// Every pixel whose primary ray a shape's own test hits lies in that shape's rectangle, in
// the shape bin of its tile (the bins list shapes by the spheres around their boxes), and a
// surface of revolution's hit is no nearer than its entry's near bound (first_hits skips it
// behind nearer hits). `min_hits` (-1: a twentieth of the pixels) keeps the check from
// passing on a scene whose shapes are out of sight; `hits_out` (optional) adds how many pixel
// and shape pairs hit.
template <class T>
void expect_shape_bins_hold_every_hit(const Scene& scene, int width, int height, int spp,
                                      int min_hits = -1, int* hits_out = nullptr) {
  RenderOptions o;
  o.width = width;
  o.height = height;
  o.spp = spp;
  o.seed = 5;
  const LecturePipeline<T> pipeline(prepare_scene<T>(scene, o, 0));
  const PreparedScene<T>& p = pipeline.scene();
  ASSERT_FALSE(p.shape_bins.empty());
  std::map<std::pair<int, int>, const ScreenBinEntry*> entry;
  for (int t = 0; t < p.shape_bins.tiles_x * p.shape_bins.tiles_y; ++t)
    for (const ScreenBinEntry& e : p.shape_bins.of_tile(t)) entry[{t, e.sphere}] = &e;
  const Tracer<T> tracer(p);
  int hits = 0, revsurf_hits = 0;
  for (int pass = 0; pass < spp; ++pass)
    for (int r = 0; r < height; ++r)
      for (int x = 0; x < width; ++x) {
        const auto d = tracer.primary_direction(pipeline.screen_point_of(x, r, pass));
        ASSERT_TRUE(d);
        const int tile = (r / kTileSize) * p.shape_bins.tiles_x + x / kTileSize;
        for (int k = 0; k < static_cast<int>(p.shapes.size()); ++k) {
          const T t = shape_t(p.shapes[k], p.eye, *d, p.shape_base() + k, Origin{});
          if (!(t > 0)) continue;
          ++hits;
          auto it = entry.find({tile, k});
          ASSERT_NE(it, entry.end()) << "shape " << k << " pixel " << x << "," << r;
          const ScreenBinEntry& e = *it->second;
          EXPECT_TRUE(x >= e.x0 && x <= e.x1 && r >= e.r0 && r <= e.r1)
              << "shape " << k << " pixel " << x << "," << r;
          if (p.shapes[k].kind != PreparedShape<T>::revsurf) continue;
          ++revsurf_hits;
          EXPECT_LE(static_cast<double>(e.near), static_cast<double>(t))
              << "shape " << k << " pixel " << x << "," << r;
        }
      }
  EXPECT_GE(hits, min_hits < 0 ? width * height / 20 : min_hits);
  if (min_hits < 0) {
    EXPECT_GT(revsurf_hits, 0) << "surfaces of revolution in sight";
  }
  if (hits_out) *hits_out += hits;
}

TEST(KindsExactness, ShapeBinsHoldEveryPixelAShapeTestHits) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    Rng rng(300 + seed);
    Scene scene = kinds_scene(rng, false);
    for (const glm::dvec3& eye : {kEyes[0], kEyes[1], kEyes[2]}) {
      SCOPED_TRACE(seed_and_eye(seed, eye));
      scene.cameras[0].viewpoint = eye;
      expect_shape_bins_hold_every_hit<double>(scene, 64, 48, 1);
      expect_shape_bins_hold_every_hit<float>(scene, 64, 48, 1);
      expect_shape_bins_hold_every_hit<double>(scene, 40, 30, 3);
    }
  }
}

// Every pixel whose reflection ray off a plane with mirror bins meets a shape (by the shape's
// own test, on the ray the tracer sends) lies in that shape's rectangle in the plane's
// mirror bins over shapes, and a surface of revolution's hit is no nearer than mirror_near
// of its entry (bounce_hits skips it behind nearer hits).
template <class T>
int expect_mirror_shape_bins_hold_every_hit(const Scene& scene, int width, int height,
                                            int& revsurf_hits) {
  RenderOptions o;
  o.width = width;
  o.height = height;
  const LecturePipeline<T> pipeline(prepare_scene<T>(scene, o, 0));
  const PreparedScene<T>& p = pipeline.scene();
  const Tracer<T> tracer(p);
  int hits = 0;
  for (int r = 0; r < height; ++r)
    for (int x = 0; x < width; ++x) {
      const auto d = tracer.primary_direction(pipeline.screen_point_of(x, r, 0));
      if (!d) continue;
      const Hit<T> first = tracer.closest(p.eye, *d, Origin{}, p.max_dist);
      const int j = first.object - p.plane_base();
      if (first.object < 0 || j < 0 || j >= static_cast<int>(p.mirror_shape_bins.size()) ||
          p.mirror_shape_bins[j].empty())
        continue;
      const auto bounce = tracer.primary_bounce(*d, first);
      if (!bounce) continue;
      const glm::dvec3 at = glm::abs(glm::dvec3(bounce->origin));
      if (!(std::max({at.x, at.y, at.z}) <= p.mirror_reach)) continue;
      const ScreenBins& bins = p.mirror_shape_bins[j];
      const int tile = (r / kTileSize) * bins.tiles_x + x / kTileSize;
      for (int k = 0; k < static_cast<int>(p.shapes.size()); ++k) {
        const int index = p.shape_base() + k;
        const T t = shape_t(p.shapes[k], bounce->origin, bounce->dir, index, bounce->from);
        if (!(t > 0)) continue;
        ++hits;
        bool listed = false;
        for (const ScreenBinEntry& e : bins.of_tile(tile)) {
          if (!(e.sphere == k && x >= e.x0 && x <= e.x1 && r >= e.r0 && r <= e.r1)) continue;
          listed = true;
          if (p.shapes[k].kind == PreparedShape<T>::revsurf) {
            ++revsurf_hits;
            EXPECT_LE(mirror_near(e.near, static_cast<double>(first.t), p.mirror_slack),
                      static_cast<double>(t))
                << "shape " << k << " pixel " << x << "," << r << " plane " << j;
          }
        }
        EXPECT_TRUE(listed) << "shape " << k << " pixel " << x << "," << r << " plane " << j;
      }
    }
  return hits;
}

TEST(KindsExactness, MirrorBinsOverShapesHoldEveryReflectionAShapeTestHits) {
  int hits = 0, revsurf_hits = 0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    Rng rng(700 + seed);
    Scene scene = kinds_scene(rng, false);
    for (const glm::dvec3& eye : {kEyes[0], kEyes[1], kEyes[3]}) {
      SCOPED_TRACE(seed_and_eye(seed, eye));
      scene.cameras[0].viewpoint = eye;
      ASSERT_FALSE(prepare_scene<double>(scene, RenderOptions{}, 0).mirror_shape_bins.empty());
      hits += expect_mirror_shape_bins_hold_every_hit<double>(scene, 80, 60, revsurf_hits);
      hits += expect_mirror_shape_bins_hold_every_hit<float>(scene, 80, 60, revsurf_hits);
    }
  }
  EXPECT_GT(hits, 1000) << "reflections meet the shapes";
  EXPECT_GT(revsurf_hits, 100) << "reflections meet surfaces of revolution";
  std::printf("%d reflections meet shapes, %d of them surfaces of revolution\n", hits,
              revsurf_hits);
}

// A few shapes and fewer spheres than pay for a hierarchy: the screen bins alone (every
// primary ray tests a shape only where it covers the screen), and the same bytes.
TEST(KindsExactness, AFewShapesWithoutTheHierarchyHaveScreenBinsAndRenderTheSame) {
  int hits = 0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    Rng rng(40 + seed);
    const Scene full = kinds_scene(rng, seed % 2 == 1);
    for (const auto& [spheres, shapes] : {std::pair{0, 1}, std::pair{3, 2}, std::pair{7, 3}}) {
      Scene scene = full;
      scene.objects.clear();
      int kept_spheres = 0, kept_shapes = 0;
      for (const Object& o : full.objects) {
        const bool sphere = o.kind == EntityKind::sphere;
        const bool plane = o.kind == EntityKind::plane || o.kind == EntityKind::tiled_plane;
        if (sphere ? kept_spheres++ < spheres : plane || kept_shapes++ < shapes)
          scene.objects.push_back(o);
      }
      for (const glm::dvec3& eye : {kEyes[0], kEyes[1], kEyes[3]}) {
        SCOPED_TRACE("seed " + std::to_string(seed) + ", " + std::to_string(spheres) +
                     " spheres, " + std::to_string(shapes) + " shapes, eye " +
                     std::to_string(eye.x) + "," + std::to_string(eye.y) + "," +
                     std::to_string(eye.z));
        scene.cameras[0].viewpoint = eye;
        for (int spp : {1, 3}) {
          RenderOptions o;
          o.spp = spp;
          o.width = 48;
          o.height = 36;
          RenderStats stats;
          const Image fast = render_image(scene, o, 2, &stats);
          ASSERT_EQ(fast.width, o.width);
          auto has = [&](const char* part) {
            return std::find(stats.parts.begin(), stats.parts.end(), part) != stats.parts.end();
          };
          EXPECT_TRUE(has("screen-bins"));
          for (const char* part : {"bvh", "mirror-bins", "light-buffers"})
            EXPECT_FALSE(has(part)) << part;
          o.specialize = false;
          EXPECT_EQ(render_image(scene, o, 2), fast);
        }
        expect_shape_bins_hold_every_hit<double>(scene, 48, 36, 1, 0, &hits);
        expect_shape_bins_hold_every_hit<float>(scene, 48, 36, 1, 0, &hits);
      }
    }
  }
  EXPECT_GT(hits, 1000) << "the shapes are in sight";
}

// revsurf_t's first test, a sphere around the surface's cylinder, never drops a crossing:
// against the same surface without it, on rays aimed at the surface (grazing it, leaving it)
// and at the sphere's rim, from near and from far, in double and float.
template <class T>
void expect_bound_drops_no_crossing(std::uint64_t seed) {
  Rng rng(seed);
  int tested = 0, culled = 0, hits = 0, rim_hits = 0;
  for (int round = 0; round < 40; ++round) {
    const Scene scene = kinds_scene(rng, false);
    const PreparedScene<T> p = prepare_scene<T>(scene, RenderOptions{}, 0);
    for (const PreparedShape<T>& s : p.shapes) {
      if (s.kind != PreparedShape<T>::revsurf) continue;
      PreparedShape<T> unbounded = s;
      unbounded.bound_radius = std::numeric_limits<double>::infinity();
      const glm::dvec3 axis(s.normal), base(s.point);
      const double top = revsurf_top(s.surfer, static_cast<double>(s.height));
      for (int i = 0; i < 2000; ++i) {
        const double far = rng.chance(0.2) ? std::pow(2.0, rng.in(5, 40)) : rng.in(0.5, 20);
        const glm::dvec3 o = s.bound_centre + far * rng.direction();
        // A target on the surface (nudged in or out by up to 2^-30 of its radius), or on
        // the bounding sphere's rim.
        glm::dvec3 target;
        const bool rim = rng.chance(0.3);
        if (rim) {
          const glm::dvec3 to = glm::normalize(s.bound_centre - o);
          glm::dvec3 side = glm::normalize(glm::cross(to, rng.direction()));
          target = s.bound_centre + s.bound_radius * (1 + rng.in(-1e-6, 1e-6)) * side;
        } else {
          const double y = rng.in(0, top);
          glm::dvec3 u = glm::normalize(glm::cross(axis, rng.direction()));
          const double r = revsurf_radius(s.surfer, y) * (1 + rng.in(-0x1p-30, 0x1p-30));
          target = base + y * axis + r * u;
        }
        glm::dvec3 d = rng.chance(0.25) ? rng.direction() : target - o;  // or anywhere
        glm::dvec3 start = o;
        if (!rim && rng.chance(0.3)) {
          // Through the rim of one end of the surface, the part nearest the sphere, along
          // the sphere's own tangent plane there: the sharpest test of its radius.
          const double y = rng.chance(0.5) ? 0 : top;
          glm::dvec3 u = glm::normalize(glm::cross(axis, rng.direction()));
          target = base + y * axis + revsurf_radius(s.surfer, y) * (1 - 0x1p-30) * u;
          d = glm::normalize(glm::cross(target - s.bound_centre, rng.direction()));
          start = target - far * d;
        }
        if (rng.chance(0.3)) d *= std::pow(2.0, rng.in(-30, 30));
        const Vec3<T> ot(start), dt(d);
        const bool own = !rim && rng.chance(0.2);
        const Vec3<T> from = own ? Vec3<T>(target) : ot;
        const T a = revsurf_t(s, from, dt, own), b = revsurf_t(unbounded, from, dt, own);
        ASSERT_EQ(std::memcmp(&a, &b, sizeof a), 0)
            << "shape surfer " << s.surfer << ", ray " << i << ": " << a << " against " << b;
        ++tested;
        culled += !(a > 0) && glm::length(glm::cross(s.bound_centre - glm::dvec3(from),
                                                     glm::normalize(glm::dvec3(dt)))) >
                                  s.bound_radius;
        hits += b > 0;
        rim_hits += rim && b > 0;
      }
    }
  }
  EXPECT_GT(tested, 20000);
  EXPECT_GT(culled, tested / 20) << "the rays must also pass wide of the sphere";
  EXPECT_GT(hits, tested / 4);
  EXPECT_GT(rim_hits, 0) << "some rays through the rim must still meet the surface";
}

// A shape's tests work from its point, which need not lie near it: a triangle in a plane
// written through a point 1e17 away has its vertices, and its hits, rounded at that scale.
// The culling structures are widened for the scale of that point too, so the pixels the
// loop gives are the pixels the render gives (they once differed in 791 of 1,200).
TEST(KindsExactness, AShapeWhosePointLiesFarAwayRendersAsTheLoop) {
  for (const char* point : {"1e17 0 -8", "0 3e12 -8", "-5e15 -5e15 -8"}) {
    SCOPED_TRACE(point);
    const Scene scene = test::scene_from(
        std::string("camera c { pixeldim 40 30 worlddim 8 6 viewpoint 4 3 5 }\n"
                    "material red { ambient 3 .5 .5 diffuse .5 .5 .5 }\n"
                    "light { location 4 6 0 }\n"
                    "sphere s { material red center 2 1 -6 radius .5 }\n"
                    "triangle x { material red normal 0 0 1 point ") +
        point + " vertex1 3 2.5 -8 vertex2 5.4 2.5 -8 vertex3 4.2 4.8 -8 }\n");
    for (Precision precision : {Precision::f64, Precision::f32}) {
      RenderOptions o;
      o.precision = precision;
      RenderStats stats;
      const Image fast = render_image(scene, o, 2, &stats);
      EXPECT_NE(std::find(stats.parts.begin(), stats.parts.end(), "screen-bins"),
                stats.parts.end());
      o.specialize = false;
      EXPECT_EQ(render_image(scene, o, 2), fast);
    }
  }
}

TEST(KindsExactness, TheRevsurfBoundDropsNoCrossing) {
  expect_bound_drops_no_crossing<double>(41);
  expect_bound_drops_no_crossing<float>(42);
}

// A shadow ray's revsurf test (ShadowLimit: the stepping's bracket decides where it can, the
// bisection is skipped) answers "0 < t < dist" as the crossing itself does: for rays aimed at
// the surface from near and far and leaving it, and lights just before, at and just beyond
// the crossing, far beyond it, at 0 and at infinity, in double and float.
template <class T>
void expect_shadow_limit_keeps_the_answer(std::uint64_t seed) {
  Rng rng(seed);
  int tested = 0, blocked = 0, early = 0;
  for (int round = 0; round < 30; ++round) {
    const Scene scene = kinds_scene(rng, false);
    const PreparedScene<T> p = prepare_scene<T>(scene, RenderOptions{}, 0);
    for (const PreparedShape<T>& s : p.shapes) {
      if (s.kind != PreparedShape<T>::revsurf) continue;
      const glm::dvec3 axis(s.normal), base(s.point);
      const double top = revsurf_top(s.surfer, static_cast<double>(s.height));
      for (int i = 0; i < 400; ++i) {
        const double y = rng.in(0, top);
        const glm::dvec3 u = glm::normalize(glm::cross(axis, rng.direction()));
        const glm::dvec3 target = base + y * axis + revsurf_radius(s.surfer, y) * u;
        const bool own = rng.chance(0.3);
        const double far = rng.chance(0.2) ? std::pow(2.0, rng.in(5, 30)) : rng.in(0.5, 20);
        const glm::dvec3 o = own ? target : target + far * rng.direction();
        const glm::dvec3 d = own || rng.chance(0.2) ? rng.direction() : target - o;
        const Vec3<T> ot(o), dt(d);
        const T t = revsurf_t(s, ot, dt, own);
        std::vector<T> dists = {T(0), std::numeric_limits<T>::infinity(),
                                static_cast<T>(rng.in(0, 2 * far))};
        if (t > 0) {
          const T inf = std::numeric_limits<T>::infinity();
          dists.insert(dists.end(), {t, std::nextafter(t, T(0)), std::nextafter(t, inf), t * T(0.5),
                                     t * T(2), t * T(1 + 1e-6), t * T(1 - 1e-6)});
        }
        for (const T dist : dists) {
          const T v = revsurf_t(s, ot, dt, own, ShadowLimit<T>{dist});
          const bool want = t > 0 && t < dist;
          ASSERT_EQ(v > 0 && v < dist, want)
              << "surfer " << s.surfer << " ray " << i << " own " << own << " t " << t << " dist "
              << dist << " got " << v;
          ++tested;
          blocked += want;
          early += std::memcmp(&v, &t, sizeof v) != 0;
        }
      }
    }
  }
  EXPECT_GT(tested, 30000);
  EXPECT_GT(blocked, tested / 5);
  EXPECT_GT(early, blocked / 4) << "the brackets must settle many answers";
}

TEST(KindsExactness, AShadowRaysRevsurfTestAnswersAsTheCrossingDoes) {
  expect_shadow_limit_keeps_the_answer<double>(61);
  expect_shadow_limit_keeps_the_answer<float>(62);
}

TEST(KindsExactness, ConesTallerThanTheirApexEqualTheLoop) {
  // A cone's radius 4 − 2y/3 is 0 at y = 6; these are 10 to 30 high, so they widen again
  // above their apex (|r(y)|) beyond the radius 4 of their base: their boxes must hold that.
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    Rng rng(200 + seed);
    Scene scene = kinds_scene(rng, false);
    for (int i = 0; i < 4; ++i)
      add(scene, EntityKind::revsurf, 0,
          Revsurf{1, point_in_box(rng), rng.direction(), rng.in(10, 30)});
    expect_same_answers<double>(scene, rng, 3000);
  }
}

}  // namespace
}  // namespace rayfarm
