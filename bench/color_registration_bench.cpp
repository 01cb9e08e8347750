// What colour registration costs: estimating the colour camera once as a sequence opens (8 of
// 7-Scenes' frames, 640x480), and resampling each colour image as it loads.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>

#include "datasets/dataset.h"

namespace {

const std::filesystem::path kSevenScenes = std::filesystem::path(GSLAM_SHARED_DATA_DIR) / "sevenscenes_redkitchen_first200";

std::vector<splat::RgbdFrame> spread_frames() {
  app::DatasetOptions options;
  options.color_camera = "registered";
  const app::Dataset d = app::open_dataset(kSevenScenes, options);
  std::vector<splat::RgbdFrame> frames;
  for (std::size_t k = 0; k < 8; ++k) frames.push_back(d.load(k * d.entries.size() / 8));
  return frames;
}

void BM_EstimateColourCamera(benchmark::State& state) {
  if (!std::filesystem::exists(kSevenScenes)) {
    state.SkipWithError(("no " + kSevenScenes.string() + " (../shared/data)").c_str());
    return;
  }
  const std::vector<splat::RgbdFrame> frames = spread_frames();
  for (auto _ : state) benchmark::DoNotOptimize(app::estimate_color_camera(frames).gain);
}
BENCHMARK(BM_EstimateColourCamera)->Unit(benchmark::kMillisecond);

void BM_RegisterColourFrame(benchmark::State& state) {
  splat::RgbdFrame frame;
  frame.camera.fx = frame.camera.fy = 585, frame.camera.cx = 320, frame.camera.cy = 240;
  frame.camera.width = 640, frame.camera.height = 480;
  frame.rgb.assign(640 * 480 * 3, 0.5f);
  frame.depth.assign(640 * 480, 1.0f);
  const app::ColorResampler resampler(frame.camera, {530, 530, 312.3, 240.2});
  for (auto _ : state) {
    splat::RgbdFrame f = frame;
    resampler.apply(f);
    benchmark::DoNotOptimize(f.rgb.data());
  }
}
BENCHMARK(BM_RegisterColourFrame)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
