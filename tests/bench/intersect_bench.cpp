// Ray/sphere roots: the cancellation-free form the tracer uses against the textbook one.
#include <benchmark/benchmark.h>

#include <vector>

#include "rayfarm/intersect.h"
#include "render/sampler.h"

namespace rayfarm {
namespace {

template <class T>
struct Case {
  std::vector<Vec3<T>> dirs;
  std::vector<Vec3<T>> centres;
  std::vector<T> radii;
};

// 1024 unit directions from the origin and 1024 spheres in front of it; about half hit.
template <class T>
Case<T> make_case() {
  Case<T> c;
  std::uint64_t s = 7;
  auto u = [&s] { return unit_double(mix64(s++)); };
  for (int i = 0; i < 1024; ++i) {
    glm::dvec3 d(u() - 0.5, u() - 0.5, -1);
    c.dirs.push_back(Vec3<T>(glm::normalize(d)));
    c.centres.push_back(Vec3<T>(u() * 4 - 2, u() * 4 - 2, -5 - 10 * u()));
    c.radii.push_back(static_cast<T>(0.2 + u()));
  }
  return c;
}

template <class T, bool kNaive>
void BM_SphereRoots(benchmark::State& state) {
  const Case<T> c = make_case<T>();
  const Vec3<T> o(0);
  for (auto _ : state) {
    int hits = 0;
    for (int i = 0; i < 1024; ++i) {
      auto r = kNaive ? sphere_roots_naive(o, c.dirs[i], c.centres[i], c.radii[i])
                      : sphere_roots(o, c.dirs[i], c.centres[i], c.radii[i]);
      hits += r.has_value();
    }
    benchmark::DoNotOptimize(hits);
  }
  state.SetItemsProcessed(state.iterations() * 1024);
}

BENCHMARK(BM_SphereRoots<double, false>)->Name("BM_SphereRoots/stable/double");
BENCHMARK(BM_SphereRoots<double, true>)->Name("BM_SphereRoots/naive/double");
BENCHMARK(BM_SphereRoots<float, false>)->Name("BM_SphereRoots/stable/float");
BENCHMARK(BM_SphereRoots<float, true>)->Name("BM_SphereRoots/naive/float");

}  // namespace
}  // namespace rayfarm
