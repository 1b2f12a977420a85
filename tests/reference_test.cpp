// The cpsc102 profile's hierarchy gives the plain loop's bytes: random course-like scenes
// with every object kind, translucent and reflective materials (whose stored hit points the
// program's full searches kept changing), spotlights, tiny spheres the hierarchy must leave
// to the loop, rendered both ways.
#include <string>

#include "random_scene.h"
#include "test_util.h"

namespace rayfarm {
namespace {
std::string num(double v) { return format_number(v); }
std::string vec(const glm::dvec3& v) { return num(v.x) + " " + num(v.y) + " " + num(v.z); }

// A scene in front of the screen (z < 0), as course scenes are, within the 20-unit path cap.
std::string random_course_scene(test::Rng& rng, int spheres) {
  std::string s =
      "camera c { pixeldim 64 48 worlddim 8 6 viewpoint 4 3 6 }\n"
      "material matte { ambient 1 1 1 diffuse 4 4 4 }\n"
      "material shiny { ambient .5 .5 .5 diffuse 2 2 3 specular .5 shininess 40 }\n"
      "material glass { diffuse 1 5 2 transparency .6 }\n"
      "material mirror { diffuse 1 1 1 specular .9 }\n"
      "material cloudy { ambient 1 0 0 diffuse 5 1 1 specular .3 transparency .3 }\n"
      "plane floor { material shiny normal 0 1 0 point 0 0 0 }\n"
      "tiled_plane back { material matte normal 0 0 1 point 0 0 -12 xdir 1 1 0 dimensions 1 1 "
      "altmaterial shiny }\n"
      "light l1 { location 1 8 2 emissivity 4 4 4 }\n"
      "spotlight l2 { location 7 6 0 emissivity 6 5 4 point 4 0 -5 theta 30 }\n";
  const char* materials[] = {"matte", "shiny", "glass", "mirror", "cloudy"};
  auto material = [&] { return std::string(materials[rng.below(5)]); };
  auto where = [&] { return glm::dvec3(rng.in(0, 8), rng.in(0, 6), rng.in(-10, -2)); };
  for (int i = 0; i < spheres; ++i) {
    const double r = rng.chance(0.05) ? 1e-9 : rng.in(0.1, 1.2);  // a few far too small to box
    s += "sphere s" + std::to_string(i) + " { material " + material() + " center " + vec(where()) +
         " radius " + num(r) + " }\n";
  }
  for (int i = 0; i < 6; ++i) {
    const glm::dvec3 n = rng.direction();
    s += "fplane f" + std::to_string(i) + " { material " + material() + " normal " +
         vec({n.x, n.y, std::abs(n.z) + 0.2}) + " point " + vec(where()) + " xdir 1 0 0 " +
         "dimensions " + num(rng.in(0.5, 3)) + " " + num(rng.in(0.5, 3)) + " }\n";
    s += "triangle t" + std::to_string(i) + " { material " + material() + " vertex1 " +
         vec(where()) + " vertex2 " + vec(where()) + " vertex3 " + vec(where()) + " }\n";
  }
  s += "revsurf v1 { material " + material() + " surfer 2 base " + vec(where()) +
       " direction 0 1 0 height 3 }\n";
  s += "revsurf v2 { material " + material() + " surfer 1 base " + vec(where()) +
       " direction 0.2 1 0 height 4 }\n";
  return s;
}

TEST(ReferenceProfile, HierarchyGivesTheLoopsBytesForEveryKind) {
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {  // 40 seeds passed when written
    SCOPED_TRACE(seed);
    test::Rng rng(seed);
    const Scene scene = test::scene_from(random_course_scene(rng, 40));
    for (int spp : {1, 4}) {
      RenderOptions o;
      ASSERT_FALSE(apply_option(o, "profile", "cpsc102"));
      o.spp = spp;
      RenderStats stats;
      const Image fast = test::render(scene, o, 2, &stats);
      EXPECT_NE(std::find(stats.parts.begin(), stats.parts.end(), "bvh"), stats.parts.end());
      o.specialize = false;
      EXPECT_EQ(test::render(scene, o, 2), fast);
    }
  }
}

// Reflection and transmission branch at every translucent mirror: a stack of them with a
// deep max_depth would double the rays per bounce (2^40 here). Each profile stops spawning
// past a budget per primary ray, and so renders.
TEST(BranchingRays, AStackOfTranslucentMirrorsRendersWithinABudget) {
  const Scene scene = test::scene_from(test::translucent_mirror_stack());
  for (const char* profile : {"lecture", "cpsc102"}) {
    SCOPED_TRACE(profile);
    RenderOptions o;
    ASSERT_FALSE(apply_option(o, "profile", profile));
    ASSERT_FALSE(apply_option(o, "max_depth", "40"));
    ASSERT_FALSE(apply_option(o, "max_dist", "unlimited"));
    RenderStats stats;
    const Image image = test::render(scene, o, 2, &stats);
    EXPECT_EQ(image.width, 4);
    // Without the budget: about 2^40 rays a pixel. The last level may still spawn both of
    // its rays, so the bound is twice the budget.
    EXPECT_GT(stats.reflection_rays, 12u * (1u << 13));
    EXPECT_LE(stats.reflection_rays, 12u * 2 * (1u << 14));
  }
}

}  // namespace
}  // namespace rayfarm
