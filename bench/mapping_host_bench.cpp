// The host-side work of one mapping step, as Mapper does it: the losses (value and gradient) at
// the image sizes mapping uses (half and full 640x480), and the Adam step over a map.
// Run: build/bench/mapping_host_bench [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "mapping/gaussian_adam.h"
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

// One step over a map of state.range(0) Gaussians at SH degree 0 (teddy's maps: 55K).
void adam_step(benchmark::State& state) {
  const std::size_t n = std::size_t(state.range(0));
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  splat::Gaussians map;
  map.sh_degree = 0;
  map.means.resize(n * 3);
  map.log_scales.resize(n * 3);
  map.rotations.resize(n * 4);
  map.opacity_logits.resize(n);
  map.sh.resize(n * 3);
  splat::GaussianGrads grads = map;
  for (splat::ParamGroup group : splat::kAllParamGroups) {
    for (float& v : splat::param_group(grads, group)) v = 1e-3f * u(rng);
  }
  mapping::GaussianAdam adam;
  for (auto _ : state) adam.step(map, grads);
}

void sizes(benchmark::internal::Benchmark* b) {
  b->Args({320, 240})->Args({640, 480})->Unit(benchmark::kMillisecond);
}

}  // namespace

BENCHMARK(dssim)->Apply(sizes);
BENCHMARK(l1)->Apply(sizes);
BENCHMARK(adam_step)->Arg(55000)->Arg(200000)->Unit(benchmark::kMillisecond);

int main(int argc, char** argv) {
  // As in gslam, a rasterizer exists: making one keeps freed frame-sized buffers in the heap
  // (splat/src/heap_tuning.h), without which every loss call would page-fault its buffers in.
  const auto rasterizer = splat::make_cpu_rasterizer();
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
