// Forward, forward+backward and forward+pose Jacobian (what Gauss-Newton tracking calls) on
// the donut workload (bench/donut_workload.h), on every backend that can run here (cpu; vulkan
// when a device exists, and vulkan_portable, its deterministic backward, where the device has
// float atomics), in one table.
// Run: build/bench/rasterizer_bench [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "donut_workload.h"
#include "mapping/gaussian_adam.h"
#include "splat/error.h"
#include "splat/losses.h"
#include "splat/rasterizer.h"
#include "splat/resident_map.h"
#include "splat/vulkan_rasterizer.h"

namespace {

const gslam::bench::Workload* workload(std::size_t count, int width, int height) {
  static std::map<std::tuple<std::size_t, int, int>, std::optional<gslam::bench::Workload>> cache;
  auto key = std::make_tuple(count, width, height);
  if (!cache.count(key)) cache[key] = gslam::bench::donut_workload(count, width, height);
  return cache[key] ? &*cache[key] : nullptr;
}

// One rasterizer per backend for the whole run (Vulkan pipelines are built once), destroyed
// before main returns, while the GPU driver is surely still loaded (as tests/support does).
std::map<std::string, std::unique_ptr<splat::Rasterizer>> backends;

splat::Rasterizer* backend(const std::string& name) {
  auto& r = backends[name];
  if (!r) {
    splat::VulkanOptions options;
    options.float_atomics = name != "vulkan_portable";
    r = name == "cpu" ? splat::make_cpu_rasterizer() : splat::make_vulkan_rasterizer(options);
  }
  return r.get();
}

// Bytes over the bus and time per stage of each iteration, and the backend's name.
void report(benchmark::State& state, splat::Rasterizer& rasterizer, const splat::Gaussians& g) {
  // Bytes over the bus per iteration, each way, as MiB, and the map's own size for scale.
  const splat::Rasterizer::Transfers moved = rasterizer.transfers();
  const double iterations = static_cast<double>(state.iterations()), mib = 1 << 20;
  state.counters["up_MiB"] = static_cast<double>(moved.to_device) / iterations / mib;
  state.counters["down_MiB"] = static_cast<double>(moved.to_host) / iterations / mib;
  state.counters["map_MiB"] =
      static_cast<double>((g.means.size() + g.log_scales.size() + g.rotations.size() + g.opacity_logits.size() + g.sh.size()) *
                          sizeof(float)) / mib;
  // Time per stage and iteration (Vulkan timestamps, CPU wall time), the four largest.
  std::vector<std::pair<double, std::string>> stages;
  double shaders = 0;
  for (const auto& [name, ms] : rasterizer.stage_times_ms()) stages.push_back({ms, name}), shaders += ms;
  if (!stages.empty()) state.counters["shaders_ms"] = shaders / static_cast<double>(state.iterations());
  std::sort(stages.rbegin(), stages.rend());
  for (std::size_t k = 0; k < std::min<std::size_t>(4, stages.size()); ++k) {
    state.counters[stages[k].second + "_ms"] = stages[k].first / static_cast<double>(state.iterations());
  }
  // Every stage, on stderr (the table keeps four): where a step's time goes.
  std::fprintf(stderr, "%s stages, ms per iteration:", rasterizer.name().c_str());
  for (const auto& [ms, name] : stages) std::fprintf(stderr, " %s %.3f", name.c_str(), ms / static_cast<double>(state.iterations()));
  std::fprintf(stderr, "\n");
  state.SetLabel(rasterizer.name());
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
  report(state, *rasterizer, w->gaussians);
}

// One mapping iteration (render, L1 + D-SSIM + depth loss against a frame, backward, Adam), the
// two ways: the resident map's step, where the map, the frame and the optimizer stay on the
// device, or the host loop, which uploads the map, downloads the images, computes the loss on
// the host, downloads the gradients and steps Adam on the host (the CPU backend's way).
void mapping_step(benchmark::State& state, const std::string& backend_name, bool resident) {
  const gslam::bench::Workload* w = workload(static_cast<std::size_t>(state.range(0)), static_cast<int>(state.range(1)),
                                             static_cast<int>(state.range(2)));
  if (!w) {
    state.SkipWithError(("donut map not found under " + gslam::bench::shared_data_dir()).c_str());
    return;
  }
  splat::Rasterizer* rasterizer = backend(backend_name);
  // The frame: the map's own render, darkened, so every term has a gradient.
  const splat::ForwardResult seen = rasterizer->forward(w->gaussians, w->camera, splat::images_only());
  splat::RgbdFrame frame;
  frame.camera = w->camera;
  frame.rgb = seen.rgb;
  for (float& c : frame.rgb) c *= 0.9f;
  frame.depth = seen.depth_normalized;
  const mapping::AdamConfig a;
  const splat::AdamRates rates{a.means, a.log_scales, a.rotations, a.opacity_logits, a.sh_dc, a.sh_rest, a.hyper};
  const splat::MappingLoss loss;
  splat::Gaussians map = w->gaussians;
  std::unique_ptr<splat::ResidentMap> device;
  if (resident) {
    device = rasterizer->make_resident_map(map.sh_degree);
    device->assign(map, nullptr);
    device->set_target(0, frame);
  }
  mapping::GaussianAdam adam(a);
  rasterizer->reset_stage_times();
  rasterizer->reset_transfers();
  for (auto _ : state) {
    if (resident) {
      benchmark::DoNotOptimize(device->step(0, w->camera, loss, rates, 1, false).loss);
      continue;
    }
    const splat::ForwardResult f = rasterizer->forward(map, w->camera, splat::images_only());
    splat::ImageGrads d;
    d.rgb.assign(f.rgb.size(), 0.f);
    d.alpha.assign(f.alpha.size(), 0.f);
    d.depth.assign(f.depth.size(), 0.f);
    splat::l1_loss<float>(f.rgb, frame.rgb, 3, {}, d.rgb, loss.color_weight);
    splat::dssim_loss<float>(f.rgb, frame.rgb, frame.width(), frame.height(), 3, d.rgb, loss.ssim_weight);
    splat::silhouette_depth_l1_loss<float>(f.depth, f.alpha, frame.depth, loss.depth_alpha_threshold, d.depth, d.alpha,
                                           loss.depth_weight);
    adam.step(map, rasterizer->backward(f, d).d_gaussians);
  }
  report(state, *rasterizer, w->gaussians);
}

void sizes(benchmark::internal::Benchmark* b) {
  for (long count : {100000L, 1000000L}) {
    b->Args({count, 640, 480});
    b->Args({count, 1280, 720});
  }
  b->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);
}

void mapping_sizes(benchmark::internal::Benchmark* b) {
  b->Args({100000, 640, 480});
  b->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  std::vector<std::string> backends{"cpu"};
  bool float_atomics = false;
  try {
    float_atomics = backend("vulkan")->name().find("float atomics") != std::string::npos;
    backends.push_back("vulkan");
  } catch (const splat::Error& e) {
    std::fprintf(stderr, "vulkan backend not benchmarked: %s\n", e.what());
  }
  for (const std::string& name : backends) {
    benchmark::RegisterBenchmark(("Forward/" + name).c_str(), run, name, Then::kNothing)->Apply(sizes);
    benchmark::RegisterBenchmark(("ForwardBackward/" + name).c_str(), run, name, Then::kBackward)->Apply(sizes);
    benchmark::RegisterBenchmark(("ForwardPoseJacobian/" + name).c_str(), run, name, Then::kPoseJacobian)
        ->Apply(sizes);
    benchmark::RegisterBenchmark(("MappingHostLoop/" + name).c_str(), mapping_step, name, false)->Apply(mapping_sizes);
    if (name != "cpu") {
      benchmark::RegisterBenchmark(("MappingResident/" + name).c_str(), mapping_step, name, true)->Apply(mapping_sizes);
    }
  }
  if (float_atomics) {  // the backward's other reduction, deterministic: what it costs here
    benchmark::RegisterBenchmark("ForwardBackward/vulkan_portable", run, "vulkan_portable", Then::kBackward)->Apply(sizes);
    benchmark::RegisterBenchmark("MappingResident/vulkan_portable", mapping_step, "vulkan_portable", true)
        ->Apply(mapping_sizes);
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  backends.clear();
  return 0;
}
