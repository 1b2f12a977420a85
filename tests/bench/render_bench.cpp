// The rest of a render: shading one pixel, whole images, PNG encoding, loading a big scene.
#include <benchmark/benchmark.h>

#include <fstream>
#include <sstream>

#include "bench_scenes.h"
#include "render/prepared_scene.h"
#include "rayfarm/image_io.h"
#include "rayfarm/load.h"
#include "rayfarm/model_parser.h"
#include "rayfarm/render.h"
#include "render/tracer.h"

namespace rayfarm {
namespace {

// One primary ray with everything it spawns (shadows, reflections), cycling over the image.
void BM_ShadePixel(benchmark::State& state) {
  const Scene scene = bench::load_bundled("scenes/cho.txt");
  const PreparedScene<double> p = prepare_scene<double>(scene, RenderOptions{}, 0);
  Tracer<double> tracer(p);
  int x = 0, y = 0;
  for (auto _ : state) {
    glm::dvec3 c = tracer.primary({x / 799.0 * p.world_width, y / 599.0 * p.world_height, 0});
    benchmark::DoNotOptimize(c);
    if (++x == 800) {
      x = 0;
      if (++y == 600) y = 0;
    }
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ShadePixel);

// Whole 800x600 renders on the given threads (no PNG).
void render_scene(benchmark::State& state, const Scene& scene) {
  RenderStats stats;
  for (auto _ : state) {
    Image image = render_image(scene, RenderOptions{}, static_cast<int>(state.range(0)), &stats);
    benchmark::DoNotOptimize(image.rgb.data());
  }
  state.counters["Mrays/s"] =
      benchmark::Counter(static_cast<double>(stats.total_rays()) * state.iterations() / 1e6,
                         benchmark::Counter::kIsRate);
}

void BM_RenderCho(benchmark::State& state) {
  render_scene(state, bench::load_bundled("scenes/cho.txt"));
}
BENCHMARK(BM_RenderCho)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_RenderGrid8000(benchmark::State& state) {
  render_scene(state, bench::load_bundled("scenes/grid-8000.txt"));
}
BENCHMARK(BM_RenderGrid8000)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_RenderRandom100k(benchmark::State& state) {
  render_scene(state, bench::random_spheres(100000));
}
BENCHMARK(BM_RenderRandom100k)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

// Scene preparation with the hierarchy (conversion + build), 100,000 spheres.
void BM_Prepare100k(benchmark::State& state) {
  const Scene scene = bench::random_spheres(100000);
  for (auto _ : state) {
    auto p = prepare_scene<double>(scene, RenderOptions{}, 0, static_cast<int>(state.range(0)));
    benchmark::DoNotOptimize(p.bvh.nodes.data());
  }
}
BENCHMARK(BM_Prepare100k)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

void BM_EncodePng(benchmark::State& state) {
  const Image image = render_image(bench::load_bundled("scenes/cho.txt"), RenderOptions{}, 2);
  std::size_t size = 0;
  for (auto _ : state) size = encode_image(image, ImageFormat::png).size();
  state.counters["bytes"] = static_cast<double>(size);
}
BENCHMARK(BM_EncodePng)->Unit(benchmark::kMillisecond);

// Parsing and checking a 100,000-sphere model file (about 7 MB) from memory.
// Arg 0: with the parsed description (what converters need); 1: the scene only (render).
void BM_LoadScene100k(benchmark::State& state) {
  const std::string text = bench::random_spheres_text(100000);
  const LoadDetail detail = state.range(0) ? LoadDetail::scene : LoadDetail::full;
  for (auto _ : state) {
    LoadedScene loaded = load_scene(text, detail);
    benchmark::DoNotOptimize(loaded.scene->objects.data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(text.size()));
}
BENCHMARK(BM_LoadScene100k)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_LoadGrid8000(benchmark::State& state) {
  std::ifstream in(RAYFARM_SOURCE_DIR "/scenes/grid-8000.txt", std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  const std::string text = s.str();
  for (auto _ : state) {
    LoadedScene loaded = load_scene(text);
    benchmark::DoNotOptimize(loaded.scene->objects.data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(text.size()));
}
BENCHMARK(BM_LoadGrid8000)->Unit(benchmark::kMillisecond);

// The two stages of the full loader on the 100,000-sphere text: parsing to the description,
// then checking and building the scene.
void BM_ParseModel100k(benchmark::State& state) {
  const std::string text = bench::random_spheres_text(100000);
  for (auto _ : state) {
    Diagnostics diags;
    SceneDesc desc = parse_model(text, diags);
    benchmark::DoNotOptimize(desc.entities.data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(text.size()));
}
BENCHMARK(BM_ParseModel100k)->Unit(benchmark::kMillisecond);

void BM_BuildScene100k(benchmark::State& state) {
  const std::string text = bench::random_spheres_text(100000);
  Diagnostics parsed;
  const SceneDesc desc = parse_model(text, parsed);
  for (auto _ : state) {
    Diagnostics diags;
    auto scene = build_scene(desc, diags);
    benchmark::DoNotOptimize(scene->objects.data());
  }
}
BENCHMARK(BM_BuildScene100k)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace rayfarm
