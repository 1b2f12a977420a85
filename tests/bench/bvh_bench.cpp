// The sphere hierarchy: build time, and closest-hit / shadow queries against the plain loop
// (the crossover sets kBvhMinSpheres).
#include <benchmark/benchmark.h>

#include <vector>

#include "bench_scenes.h"
#include "accel/bvh.h"
#include "render/prepared_scene.h"
#include "render/tracer.h"

namespace rayfarm {
namespace {

std::vector<BvhBox> boxes_of(const Scene& s) {
  std::vector<BvhBox> boxes;
  for (const Object& o : s.objects)
    if (const Sphere* sp = o.as<Sphere>())
    boxes.push_back({sp->center - sp->radius, sp->center + sp->radius});
  return boxes;
}

void BM_BvhBuild(benchmark::State& state) {
  const auto boxes = boxes_of(bench::random_spheres(static_cast<int>(state.range(0))));
  BvhBuildOptions options;
  options.threads = static_cast<int>(state.range(1));
  Bvh bvh;
  for (auto _ : state) {
    bvh = build_bvh(boxes, options);
    benchmark::DoNotOptimize(bvh.nodes.data());
  }
  state.counters["nodes"] = bvh.stats.nodes;
  state.counters["depth"] = bvh.stats.depth;
  state.counters["mean_leaf"] = bvh.stats.mean_leaf;
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_BvhBuild)->ArgsProduct({{1000, 10000, 100000}, {1, 2}})->Unit(benchmark::kMillisecond);

// Rays of a 80x60 grid of the camera's pixels, and where they hit.
struct Rays {
  std::vector<glm::dvec3> dirs;
  std::vector<glm::dvec3> points;  // hit points, for shadow rays
  std::vector<Origin> from;
};

template <bool kBvh>
PreparedScene<double> prepared(int spheres) {
  RenderOptions o;
  o.specialize = false;  // no hierarchy: add it (or not) here, whatever the count
  PreparedScene<double> p = prepare_scene<double>(bench::random_spheres(spheres), o, 0);
  if (kBvh) build_sphere_bvh(p, 1);
  return p;
}

Rays primary_rays(const PreparedScene<double>& p) {
  Rays r;
  Tracer<double> tracer(p);
  for (int y = 0; y < 60; ++y)
    for (int x = 0; x < 80; ++x) {
      glm::dvec3 target(x / 79.0 * p.world_width, y / 59.0 * p.world_height, 0);
      glm::dvec3 d = glm::normalize(target - p.eye);
      r.dirs.push_back(d);
      Hit<double> h = tracer.closest(p.eye, d, {}, std::numeric_limits<double>::infinity());
      if (h.object >= 0 && h.object < static_cast<int>(p.spheres.size())) {
        r.points.push_back(p.eye + h.t * d);
        r.from.push_back({h.object, false});
      }
    }
  return r;
}

template <bool kBvh>
void BM_Closest(benchmark::State& state) {
  const PreparedScene<double> p = prepared<kBvh>(static_cast<int>(state.range(0)));
  const Rays rays = primary_rays(p);
  Tracer<double> tracer(p);
  std::size_t i = 0;
  for (auto _ : state) {
    Hit<double> h =
        tracer.closest(p.eye, rays.dirs[i], {}, std::numeric_limits<double>::infinity());
    benchmark::DoNotOptimize(h);
    if (++i == rays.dirs.size()) i = 0;
  }
  state.SetItemsProcessed(state.iterations());
}

template <bool kBvh>
void BM_Occluded(benchmark::State& state) {
  const PreparedScene<double> p = prepared<kBvh>(static_cast<int>(state.range(0)));
  const Rays rays = primary_rays(p);
  if (rays.points.empty()) {
    state.SkipWithError("no ray hits a sphere");
    return;
  }
  Tracer<double> tracer(p);
  const glm::dvec3 light = p.lights[0].location;
  std::size_t i = 0;
  for (auto _ : state) {
    const glm::dvec3 l = light - rays.points[i];
    const double dist = glm::length(l);
    bool blocked = tracer.occluded(rays.points[i], l / dist, rays.from[i], dist);
    benchmark::DoNotOptimize(blocked);
    if (++i == rays.points.size()) i = 0;
  }
  state.SetItemsProcessed(state.iterations());
}

const std::vector<std::int64_t> kCounts = {2, 4, 6, 8, 12, 16, 32, 64, 1000, 100000};
BENCHMARK(BM_Closest<false>)
    ->Name("BM_Closest/loop")
    ->ArgsProduct({{2, 4, 6, 8, 12, 16, 32, 64, 1000}});
BENCHMARK(BM_Closest<true>)->Name("BM_Closest/bvh")->ArgsProduct({kCounts});
BENCHMARK(BM_Occluded<false>)
    ->Name("BM_Occluded/loop")
    ->ArgsProduct({{2, 4, 6, 8, 12, 16, 32, 64, 1000}});
BENCHMARK(BM_Occluded<true>)->Name("BM_Occluded/bvh")->ArgsProduct({kCounts});

}  // namespace
}  // namespace rayfarm
