#include "commands/reconstruct_command.h"

#include <chrono>
#include <cstdio>

#include "commands/interrupt.h"
#include "commands/progress.h"
#include "commands/run_outputs.h"
#include "io/slam_config_io.h"
#include "slam/slam_system.h"
#include "datasets/synthetic_sequence.h"
#include "splat/error.h"

namespace app {
int run_reconstruct(const ReconstructOptions& o) {
  const SlamConfig config = load_slam_config(o.config);  // first: a bad file costs nothing
  if (o.print_config) {
    std::printf("%s\n", slam_config_to_json(config).dump(2).c_str());
    return 0;
  }
  if (o.out.empty()) throw splat::Error("reconstruct: --out is required");
  std::filesystem::create_directories(o.out);
  std::filesystem::path input = o.dataset;
  if (input.empty()) {
    input = o.out / "synthetic_input";
    std::fprintf(stderr, "no dataset given: generating the bundled synthetic sequence into %s\n", input.c_str());
    write_synthetic_sequence(input, SyntheticOptions{});
  }
  const Dataset dataset = open_dataset(input, o.dataset_options);
  std::fprintf(stderr, "dataset %s (%s): %zu frames at %dx%d%s", input.c_str(), dataset.format.c_str(),
               dataset.entries.size(), dataset.intrinsics.width, dataset.intrinsics.height,
               dataset.has_ground_truth() ? ", with ground truth" : "");
  if (dataset.skipped_missing > 0) std::fprintf(stderr, ", %zu listed files missing (skipped)", dataset.skipped_missing);
  if (dataset.unmatched > 0) std::fprintf(stderr, ", %zu colour frames without depth", dataset.unmatched);
  std::fprintf(stderr, "\n");

  std::string note;
  auto rasterizer = make_rasterizer(o.backend, note);
  std::fprintf(stderr, "%s\n", note.c_str());
  SlamSystem slam(*rasterizer, config);

  RunOutputs outputs(o.out, input.string(), *rasterizer, o.overwrite);
  // What the run read, so that eval (or a later reader) uses the same camera and depth units.
  const splat::Camera& k = dataset.intrinsics;
  outputs.extra()["input"] = {{"dataset", std::filesystem::absolute(input).string()},
                              {"format", dataset.format},
                              {"intrinsics", {{"fx", k.fx}, {"fy", k.fy}, {"cx", k.cx}, {"cy", k.cy}, {"width", k.width}, {"height", k.height}}},
                              {"depth_scale", dataset.depth_scale},
                              {"max_frames", o.dataset_options.max_frames},
                              {"config", slam_config_to_json(config)}};
  // Ctrl-C or SIGTERM: stop taking frames (or end the sweep) and write complete outputs.
  const InterruptGuard interrupt;
  Progress progress("reconstruct", dataset.entries.size(), "frames");
  const std::size_t every = static_cast<std::size_t>(std::max(1, o.checkpoint_every));
  for (std::size_t i = 0; i < dataset.entries.size() && !InterruptGuard::interrupted(); ++i) {
    const auto load_start = std::chrono::steady_clock::now();
    const splat::RgbdFrame frame = dataset.load(i);
    const double loading_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - load_start).count();
    const FrameRecord record = slam.process(frame);
    if (!record.tracked) std::fprintf(stderr, "\nframe %zu: tracking failed (%s)\n", i, record.reason.c_str());
    outputs.add(record, loading_ms);
    progress.update(i + 1, std::to_string(record.gaussians) + " Gaussians, " + std::to_string(slam.keyframes()) + " keyframes");
    if ((i + 1) % every == 0) {
      outputs.update_poses(slam.trajectory());
      outputs.checkpoint(*slam.map(), slam.keyframes(), (i + 1) % (5 * every) == 0);
    }
  }
  progress.finish();
  const std::size_t refine_frames = slam.refine_frames().size();
  if (config.refine_passes > 0 && refine_frames > 0 && !InterruptGuard::interrupted()) {
    const std::size_t visits = refine_frames * static_cast<std::size_t>(config.refine_passes);
    Progress refine_progress("refine", visits, "frame visits");
    const SlamSystem::Refinement refined = slam.refine_map(
        [&](std::size_t i) { return dataset.load(i); },
        [&](std::size_t done, std::size_t) { refine_progress.update(done, std::to_string(slam.map()->size()) + " Gaussians"); },
        [] { return InterruptGuard::interrupted(); });
    refine_progress.finish();
    // The camera's vignetting as the refinement estimated it: gslam eval renders through it.
    const mapping::Vignetting vignetting = slam.vignetting();
    outputs.extra()["vignetting"] = {{"k1", vignetting.k1}, {"k2", vignetting.k2}};
    outputs.extra()["refinement"] = {{"frames", refined.frames}, {"passes", config.refine_passes},
                                     {"iterations_per_visit", config.refine_iterations}, {"pruned", refined.pruned},
                                     {"visits", refined.visits}, {"stopped_early", refined.stopped},
                                     {"seconds", refine_progress.elapsed_seconds()}};
    std::fprintf(stderr, "refined the map: %zu frames x %d passes in %.1f s, %zu Gaussians pruned\n",
                 refined.frames, config.refine_passes, refine_progress.elapsed_seconds(), refined.pruned);
  }
  outputs.update_poses(slam.trajectory());  // keyframes moved by mapping carry their frames
  outputs.set_mapping(slam.mapping_totals());
  outputs.extra()["interrupted"] = InterruptGuard::interrupted();
  if (InterruptGuard::interrupted()) std::fprintf(stderr, "interrupted: writing what was done\n");
  std::vector<StampedPose> truth;
  for (const auto& e : dataset.entries) {
    if (e.T_world_cam_truth) truth.push_back({e.timestamp, *e.T_world_cam_truth});
  }
  const std::shared_ptr<const splat::Gaussians> map = slam.map();
  outputs.finish(*map, slam.keyframes(), *rasterizer, dataset.intrinsics, truth);
  const std::size_t frames = outputs.records().size();
  std::printf("reconstructed %zu frames (%zu keyframes, %zu tracking failures) into %zu Gaussians at %.2f frames/s -> %s\n",
              frames, slam.keyframes(), outputs.failures(), map->size(),
              static_cast<double>(frames) / progress.elapsed_seconds(), o.out.c_str());
  return 0;
}

}  // namespace app
