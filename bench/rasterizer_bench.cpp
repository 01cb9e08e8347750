// Forward and forward+backward on the donut workload (bench/donut_workload.h).
// Run: build/bench/rasterizer_bench [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <map>
#include <memory>

#include "donut_workload.h"
#include "splat/rasterizer.h"

namespace {

const gslam::bench::Workload* workload(std::size_t count, int width, int height) {
  static std::map<std::tuple<std::size_t, int, int>, std::optional<gslam::bench::Workload>> cache;
  auto key = std::make_tuple(count, width, height);
  if (!cache.count(key)) cache[key] = gslam::bench::donut_workload(count, width, height);
  return cache[key] ? &*cache[key] : nullptr;
}

void run(benchmark::State& state, bool backward) {
  const std::size_t count = static_cast<std::size_t>(state.range(0));
  const int width = static_cast<int>(state.range(1)), height = static_cast<int>(state.range(2));
  const gslam::bench::Workload* w = workload(count, width, height);
  if (!w) {
    state.SkipWithError(("donut map not found under " + gslam::bench::shared_data_dir()).c_str());
    return;
  }
  auto rasterizer = splat::make_cpu_rasterizer();
  splat::ImageGrads d_image;
  const std::size_t pixels = static_cast<std::size_t>(width) * height;
  d_image.rgb.assign(pixels * 3, 1e-3f);
  d_image.alpha.assign(pixels, 1e-3f);
  d_image.depth.assign(pixels, 1e-3f);
  double covered = 0;
  std::size_t intersections = 0;
  for (auto _ : state) {
    splat::ForwardResult f = rasterizer->forward(w->gaussians, w->camera, {});
    if (backward) benchmark::DoNotOptimize(rasterizer->backward(f, d_image));
    covered = 0;
    for (float a : f.alpha) covered += a > 0.5f;
    intersections = f.stats.intersections;
    benchmark::DoNotOptimize(f.rgb.data());
  }
  state.counters["coverage"] = covered / static_cast<double>(pixels);
  state.counters["isects"] = static_cast<double>(intersections);
  state.SetLabel(rasterizer->name());
}

void BM_CpuForward(benchmark::State& state) { run(state, false); }
void BM_CpuForwardBackward(benchmark::State& state) { run(state, true); }

void sizes(benchmark::internal::Benchmark* b) {
  for (long count : {100000L, 1000000L}) {
    b->Args({count, 640, 480});
  }
  b->Args({100000L, 1280, 720});
  b->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);
}

}  // namespace

BENCHMARK(BM_CpuForward)->Apply(sizes);
BENCHMARK(BM_CpuForwardBackward)->Apply(sizes);
BENCHMARK_MAIN();
