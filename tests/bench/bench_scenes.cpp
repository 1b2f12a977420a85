// In-memory benchmark scenes.
#include "bench_scenes.h"

#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "rayfarm/load.h"
#include "render/sampler.h"

namespace rayfarm::bench {
namespace {

struct Rng {
  std::uint64_t state;
  double uniform(double lo, double hi) { return lo + (hi - lo) * unit_double(mix64(state++)); }
};

Material material(const char* name, glm::dvec3 ambient, glm::dvec3 diffuse, double specular) {
  Material m;
  m.name = name;
  m.ambient = ambient;
  m.diffuse = diffuse;
  m.specular = glm::dvec3(specular);
  return m;
}

}  // namespace

Scene random_spheres(int count, std::uint64_t seed) {
  Scene s;
  Camera cam;
  cam.name = "cam";
  cam.width = 800;
  cam.height = 600;
  cam.world_width = 8;
  cam.world_height = 6;
  cam.viewpoint = {4, 3, 5};
  s.cameras.push_back(cam);
  s.materials = {material("chrome", {1, 1, 1}, {.1, .1, .1}, .8),
                 material("red", {5, 1, 1}, {.8, .15, .1}, 0),
                 material("green", {1, 4, 1}, {.15, .7, .2}, .3),
                 material("blue", {1, 1.5, 5}, {.1, .25, .8}, 0),
                 material("floor", {2, 2, 2}, {.5, .5, .5}, 0)};
  for (auto [name, at, e] : {std::tuple{"key", glm::dvec3(-6, 30, 0), glm::dvec3(12, 12, 12)},
                             std::tuple{"fill", glm::dvec3(14, 8, -4), glm::dvec3(4, 4, 4.5)}}) {
    Light& l = s.lights.emplace_back();
    l.name = name;
    l.location = at;
    l.emissivity = e;
  }
  Object& floor = s.objects.emplace_back();
  floor.name = "ground";
  floor.kind = EntityKind::plane;
  floor.material = 4;
  floor.shape = Plane{};
  Rng rng{seed * 0x9e3779b97f4a7c15ULL};
  for (int i = 0; i < count; ++i) {
    Sphere sp;
    // Uniform in the view frustum between 2 and 40 units behind the window.
    const double depth = rng.uniform(2, 40), k = (5 + depth) / 5;
    sp.center = {4 + (rng.uniform(0, 8) - 4) * k, 3 + (rng.uniform(0, 6) - 3) * k, -depth};
    sp.radius = rng.uniform(0.04, 0.14);
    if (sp.center.y < sp.radius) sp.center.y = sp.radius + rng.uniform(0, 1);
    Object& o = s.objects.emplace_back();
    o.name = "s" + std::to_string(i);
    o.kind = EntityKind::sphere;
    o.material = static_cast<int>(rng.uniform(0, 4));
    o.shape = sp;
  }
  return s;
}

std::string random_spheres_text(int count, std::uint64_t seed) {
  Scene s = random_spheres(count, seed);
  std::string out =
      "camera cam { pixeldim 800 600 worlddim 8 6 viewpoint 4 3 5 }\n"
      "material chrome { ambient 1 1 1 diffuse .1 .1 .1 specular .8 .8 .8 }\n"
      "material red { ambient 5 1 1 diffuse .8 .15 .1 }\n"
      "material green { ambient 1 4 1 diffuse .15 .7 .2 specular .3 .3 .3 }\n"
      "material blue { ambient 1 1.5 5 diffuse .1 .25 .8 }\n"
      "material floor { ambient 2 2 2 diffuse .5 .5 .5 }\n"
      "light key { location -6 30 0 emissivity 12 12 12 }\n"
      "light fill { location 14 8 -4 emissivity 4 4 4.5 }\n"
      "plane ground { material floor normal 0 1 0 point 0 0 0 }\n";
  char line[200];
  for (const Object& o : s.objects) {
    const Sphere* sp = o.as<Sphere>();
    if (!sp) continue;
    std::snprintf(line, sizeof line,
                  "sphere %s { material %s center %.4f %.4f %.4f radius %.4f }\n", o.name.c_str(),
                  s.materials[o.material].name.c_str(), sp->center.x, sp->center.y, sp->center.z,
                  sp->radius);
    out += line;
  }
  return out;
}

Scene load_bundled(const std::string& relative_path) {
  std::ifstream in(std::string(RAYFARM_SOURCE_DIR) + "/" + relative_path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  LoadedScene loaded = load_scene(text.str());
  if (!loaded.scene) throw std::runtime_error("cannot load " + relative_path);
  return *loaded.scene;
}

}  // namespace rayfarm::bench
