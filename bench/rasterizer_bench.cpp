// Forward, forward+backward and forward+pose Jacobian (what Gauss-Newton tracking calls) on
// the donut workload (bench/donut_workload.h), on every backend that can run here (cpu; vulkan
// when a device exists), in one table.
// Run: build/bench/rasterizer_bench [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "donut_workload.h"
#include "splat/error.h"
#include "splat/rasterizer.h"
#include "splat/vulkan_rasterizer.h"

namespace {

const gslam::bench::Workload* workload(std::size_t count, int width, int height) {
  static std::map<std::tuple<std::size_t, int, int>, std::optional<gslam::bench::Workload>> cache;
  auto key = std::make_tuple(count, width, height);
  if (!cache.count(key)) cache[key] = gslam::bench::donut_workload(count, width, height);
  return cache[key] ? &*cache[key] : nullptr;
}

// One rasterizer per backend for the whole run (Vulkan pipelines are built once).
splat::Rasterizer* backend(const std::string& name) {
  static std::map<std::string, std::unique_ptr<splat::Rasterizer>> cache;
  auto& r = cache[name];
  if (!r) r = name == "cpu" ? splat::make_cpu_rasterizer() : splat::make_vulkan_rasterizer();
  return r.get();
}

// What each timed iteration runs after the forward pass.
enum class Then { kNothing, kBackward, kPoseJacobian };

void run(benchmark::State& state, const std::string& backend_name, Then then) {
  const std::size_t count = static_cast<std::size_t>(state.range(0));
  const int width = static_cast<int>(state.range(1)), height = static_cast<int>(state.range(2));
  const gslam::bench::Workload* w = workload(count, width, height);
  if (!w) {
    state.SkipWithError(("donut map not found under " + gslam::bench::shared_data_dir()).c_str());
    return;
  }
  splat::Rasterizer* rasterizer = backend(backend_name);
  splat::ImageGrads d_image;
  const std::size_t pixels = static_cast<std::size_t>(width) * height;
  d_image.rgb.assign(pixels * 3, 1e-3f);
  d_image.alpha.assign(pixels, 1e-3f);
  d_image.depth.assign(pixels, 1e-3f);
  splat::ForwardResult f;
  std::vector<float> jacobian;  // reused, as tracking does
  rasterizer->reset_stage_times();
  rasterizer->reset_transfers();
  for (auto _ : state) {
    f = rasterizer->forward(w->gaussians, w->camera, splat::images_only());
    if (then == Then::kBackward) benchmark::DoNotOptimize(rasterizer->backward(f, d_image));
    if (then == Then::kPoseJacobian) {
      rasterizer->pose_jacobian(f, jacobian);
      benchmark::DoNotOptimize(jacobian.data());
    }
    benchmark::DoNotOptimize(f.rgb.data());
  }
  // Outside the timed loop: at GPU speeds this scan would be a visible share of a forward.
  double covered = 0;
  for (float a : f.alpha) covered += a > 0.5f;
  const std::size_t intersections = f.stats.intersections;
  state.counters["coverage"] = covered / static_cast<double>(pixels);
  state.counters["isects"] = static_cast<double>(intersections);
  // Bytes over the bus per iteration, each way, as MiB, and the map's own size for scale.
  const splat::Rasterizer::Transfers moved = rasterizer->transfers();
  const double iterations = static_cast<double>(state.iterations()), mib = 1 << 20;
  state.counters["up_MiB"] = static_cast<double>(moved.to_device) / iterations / mib;
  state.counters["down_MiB"] = static_cast<double>(moved.to_host) / iterations / mib;
  const splat::Gaussians& g = w->gaussians;
  state.counters["map_MiB"] =
      static_cast<double>((g.means.size() + g.log_scales.size() + g.rotations.size() + g.opacity_logits.size() + g.sh.size()) *
                          sizeof(float)) / mib;
  // Time per stage and iteration (Vulkan timestamps, CPU wall time), the four largest.
  std::vector<std::pair<double, std::string>> stages;
  for (const auto& [name, ms] : rasterizer->stage_times_ms()) stages.push_back({ms, name});
  std::sort(stages.rbegin(), stages.rend());
  for (std::size_t k = 0; k < std::min<std::size_t>(4, stages.size()); ++k) {
    state.counters[stages[k].second + "_ms"] = stages[k].first / static_cast<double>(state.iterations());
  }
  state.SetLabel(rasterizer->name());
}

void sizes(benchmark::internal::Benchmark* b) {
  for (long count : {100000L, 1000000L}) {
    b->Args({count, 640, 480});
    b->Args({count, 1280, 720});
  }
  b->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  std::vector<std::string> backends{"cpu"};
  try {
    backend("vulkan");
    backends.push_back("vulkan");
  } catch (const splat::Error& e) {
    std::fprintf(stderr, "vulkan backend not benchmarked: %s\n", e.what());
  }
  for (const std::string& name : backends) {
    benchmark::RegisterBenchmark(("Forward/" + name).c_str(), run, name, Then::kNothing)->Apply(sizes);
    benchmark::RegisterBenchmark(("ForwardBackward/" + name).c_str(), run, name, Then::kBackward)->Apply(sizes);
    benchmark::RegisterBenchmark(("ForwardPoseJacobian/" + name).c_str(), run, name, Then::kPoseJacobian)
        ->Apply(sizes);
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
