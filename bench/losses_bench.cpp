// The mapping step's host-side losses at the image sizes mapping uses (half and full 640x480),
// value and gradient together, as Mapper calls them.
// Run: build/bench/losses_bench [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "splat/losses.h"
#include "splat/rasterizer.h"

namespace {

struct Images {
  std::vector<float> pred, target, grad;
};

Images random_images(int width, int height) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  Images im;
  const std::size_t n = std::size_t(width) * height * 3;
  for (std::size_t i = 0; i < n; ++i) {
    im.target.push_back(u(rng));
    im.pred.push_back(0.5f * (im.target.back() + u(rng)));
  }
  im.grad.assign(n, 0.f);
  return im;
}

void dssim(benchmark::State& state) {
  const int width = int(state.range(0)), height = int(state.range(1));
  Images im = random_images(width, height);
  for (auto _ : state) {
    benchmark::DoNotOptimize(splat::dssim_loss<float>(im.pred, im.target, width, height, 3, im.grad, 0.2));
  }
}

void l1(benchmark::State& state) {
  const int width = int(state.range(0)), height = int(state.range(1));
  Images im = random_images(width, height);
  for (auto _ : state) benchmark::DoNotOptimize(splat::l1_loss<float>(im.pred, im.target, 3, {}, im.grad));
}

void sizes(benchmark::internal::Benchmark* b) {
  b->Args({320, 240})->Args({640, 480})->Unit(benchmark::kMillisecond);
}

}  // namespace

BENCHMARK(dssim)->Apply(sizes);
BENCHMARK(l1)->Apply(sizes);

int main(int argc, char** argv) {
  // As in gslam, a rasterizer exists: making one keeps freed frame-sized buffers in the heap
  // (splat/src/heap_tuning.h), without which every loss call would page-fault its buffers in.
  const auto rasterizer = splat::make_cpu_rasterizer();
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
