// What undistorting a frame costs as it loads (TUM fr1's lens, 640x480): colour remapped
// bilinearly, depth interpolated within surfaces. Runs on the thread that loads or receives frames.
#include <benchmark/benchmark.h>

#include "datasets/lens_distortion.h"

namespace {

void BM_UndistortFr1Frame(benchmark::State& state) {
  splat::Camera raw;
  raw.fx = 517.306408, raw.fy = 516.469215, raw.cx = 318.643040, raw.cy = 255.313989;
  raw.width = 640, raw.height = 480;
  const app::Undistortion undistortion(raw, {0.262383, -0.953104, -0.005358, 0.002628, 1.163314},
                                       "fr1");
  splat::RgbdFrame frame;
  frame.camera = raw;
  frame.rgb.assign(640 * 480 * 3, 0.5f);
  frame.depth.resize(640 * 480);
  for (std::size_t i = 0; i < frame.depth.size(); ++i)
    frame.depth[i] = 1.0f + 0.001f * static_cast<float>(i % 640);
  for (auto _ : state) {
    splat::RgbdFrame f = frame;
    undistortion.apply(f);
    benchmark::DoNotOptimize(f.depth.data());
  }
}
BENCHMARK(BM_UndistortFr1Frame)->Unit(benchmark::kMillisecond);

// The copy the benchmark above makes of each frame, alone: what undistortion adds is the
// difference.
void BM_CopyFrame(benchmark::State& state) {
  splat::RgbdFrame frame;
  frame.rgb.assign(640 * 480 * 3, 0.5f);
  frame.depth.assign(640 * 480, 1.0f);
  for (auto _ : state) {
    splat::RgbdFrame f = frame;
    benchmark::DoNotOptimize(f.depth.data());
  }
}
BENCHMARK(BM_CopyFrame)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
