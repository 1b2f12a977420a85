// The ray-culling structures: building screen bins and light buffers, and shadow rays
// answered from a light buffer against the same rays through the hierarchy
// (BM_Occluded/bvh in bvh_bench.cpp).
#include <benchmark/benchmark.h>

#include <vector>

#include "bench_scenes.h"
#include "accel/light_buffer.h"
#include "render/prepared_scene.h"
#include "accel/screen_bins.h"
#include "render/tracer.h"

namespace rayfarm {
namespace {

std::vector<WidenedSphere> spheres_of(const Scene& s) {
  std::vector<WidenedSphere> out;
  for (const Object& o : s.objects)
    if (const Sphere* sp = o.as<Sphere>()) out.push_back({sp->center, sp->radius});
  return out;
}

void BM_ScreenBinsBuild(benchmark::State& state) {
  const Scene scene = bench::random_spheres(static_cast<int>(state.range(0)));
  const auto spheres = spheres_of(scene);
  const Camera& c = scene.cameras[0];
  const ScreenCamera camera{c.viewpoint, c.world_width, c.world_height, c.width, c.height, 1.5, 1.5};
  ScreenBins bins;
  for (auto _ : state) {
    bins = build_screen_bins(camera, spheres, kTileSize, 64);
    benchmark::DoNotOptimize(bins.entries.data());
  }
  state.counters["entries"] = static_cast<double>(bins.entries.size());
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_ScreenBinsBuild)->Arg(8000)->Arg(100000)->Unit(benchmark::kMillisecond);

void BM_LightBufferBuild(benchmark::State& state) {
  const Scene scene = bench::random_spheres(static_cast<int>(state.range(0)));
  const auto spheres = spheres_of(scene);
  LightBuffer lb;
  for (auto _ : state) {
    lb = build_light_buffer(scene.lights[0].location, spheres, 1e3);
    benchmark::DoNotOptimize(lb.entries.data());
  }
  state.counters["cells_per_side"] = lb.n;
  state.counters["entries"] = static_cast<double>(lb.entries.size());
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_LightBufferBuild)->Arg(8000)->Arg(100000)->Unit(benchmark::kMillisecond);

// Shadow rays to the first light from where 80x60 primary rays hit a sphere.
void BM_OccludedLightBuffer(benchmark::State& state) {
  const PreparedScene<double> p =
      prepare_scene<double>(bench::random_spheres(static_cast<int>(state.range(0))), {}, 0);
  if (p.light_buffers.empty() || p.light_buffers[0].empty()) {
    state.SkipWithError("no light buffer");
    return;
  }
  Tracer<double> tracer(p);
  std::vector<glm::dvec3> points;
  std::vector<Origin> from;
  for (int y = 0; y < 60; ++y) {
    for (int x = 0; x < 80; ++x) {
      const glm::dvec3 d = glm::normalize(
          glm::dvec3(x / 79.0 * p.world_width, y / 59.0 * p.world_height, 0) - p.eye);
      const Hit<double> h = tracer.closest(p.eye, d, {}, std::numeric_limits<double>::infinity());
      if (h.object < 0 || h.object >= static_cast<int>(p.spheres.size())) continue;
      points.push_back(p.eye + h.t * d);
      from.push_back({h.object, false});
    }
  }
  const glm::dvec3 light = p.lights[0].location;
  std::size_t i = 0;
  for (auto _ : state) {
    const glm::dvec3 l = light - points[i];
    const double dist = glm::length(l);
    bool blocked = tracer.occluded(points[i], l / dist, from[i], dist, nullptr, &p.light_buffers[0]);
    benchmark::DoNotOptimize(blocked);
    if (++i == points.size()) i = 0;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_OccludedLightBuffer)->Name("BM_Occluded/light_buffer")->Arg(1000)->Arg(100000);

}  // namespace
}  // namespace rayfarm
