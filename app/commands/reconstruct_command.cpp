#include "commands/reconstruct_command.h"

#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>

#include "commands/interrupt.h"
#include "commands/label_maps.h"
#include "commands/progress.h"
#include "commands/run_input.h"
#include "commands/run_outputs.h"
#include "io/run_checkpoint.h"
#include "io/run_folder.h"
#include "io/slam_config_io.h"
#include "slam/frame_prefetch.h"
#include "slam/slam_system.h"
#include "datasets/synthetic_sequence.h"
#include "splat/error.h"

namespace app {
namespace {
constexpr char kCheckpointFile[] = "checkpoint.bin";

// What a run reads: its dataset, dataset options and SLAM configuration; with --resume, the
// interrupted run's, from its checkpoint.
struct RunInputs {
  std::filesystem::path input;
  DatasetOptions dataset_options;
  SlamConfig config;
  int test_every = 0;
  std::optional<RunCheckpoint> checkpoint;
};

RunInputs plan_resume(const ReconstructOptions& o) {
  if (!o.dataset.empty() || !o.config.empty() || !o.dataset_options.intrinsics.empty() ||
      o.dataset_options.depth_scale > 0 || o.dataset_options.max_frames > 0 || o.test_every > 0 || o.overwrite) {
    throw splat::Error("reconstruct --resume continues with the interrupted run's dataset and configuration: "
                       "give only --out (and backend options)");
  }
  const std::filesystem::path file = o.out / kCheckpointFile;
  if (!std::filesystem::exists(file)) {
    throw splat::Error(file.string() + ": no checkpoint to resume (the run completed, or stopped before its first checkpoint)");
  }
  RunInputs plan;
  plan.checkpoint = read_run_checkpoint(file);
  const nlohmann::json& run = plan.checkpoint->run;
  if (!run.contains("extra") || !run["extra"].contains("input")) throw splat::Error(file.string() + ": records no input");
  const RecordedInput recorded = recorded_input(run["extra"]["input"], file.string());
  plan.input = recorded.dataset;
  plan.dataset_options = recorded.options;
  plan.config = slam_config_from_json(recorded.config);
  plan.test_every = recorded.test_every;
  return plan;
}

RunInputs plan_new_run(const ReconstructOptions& o) {
  RunInputs plan{o.dataset, o.dataset_options, load_slam_config(o.config), o.test_every,
                 std::nullopt};  // first: a bad file costs nothing
  if (plan.input.empty() && !o.out.empty()) {
    plan.input = o.out / "synthetic_input";
    std::fprintf(stderr, "no dataset given: generating the bundled synthetic sequence into %s\n", plan.input.c_str());
    write_synthetic_sequence(plan.input, SyntheticOptions{});
  }
  return plan;
}

}  // namespace

int run_reconstruct(const ReconstructOptions& o) {
  if (o.print_config) {
    std::printf("%s\n", slam_config_to_json(load_slam_config(o.config)).dump(2).c_str());
    return 0;
  }
  if (o.out.empty()) throw splat::Error("reconstruct: --out is required");
  RunInputs plan = o.resume ? plan_resume(o) : plan_new_run(o);
  const SlamConfig& config = plan.config;
  const std::filesystem::path& input = plan.input;
  const Dataset dataset = open_dataset(input, plan.dataset_options);
  std::fprintf(stderr, "dataset %s (%s): %s at %dx%d%s\n", input.c_str(), dataset.format.c_str(),
               dataset.frames_used().c_str(), dataset.intrinsics.width, dataset.intrinsics.height,
               dataset.has_ground_truth() ? ", with ground truth" : "");
  for (const std::string& w : dataset.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  if (const std::string color = dataset.color_note(); !color.empty()) std::fprintf(stderr, "%s\n", color.c_str());

  std::string note;
  auto rasterizer = make_rasterizer(o.backend, note);
  std::fprintf(stderr, "%s\n", note.c_str());
  SlamSystem slam(*rasterizer, config);
  const auto load = [&](std::size_t i) { return dataset.load(i); };
  std::unique_ptr<RunOutputs> outputs_owner;
  std::size_t first = 0;
  if (plan.checkpoint) {
    first = plan.checkpoint->slam.frames.size();
    if (first > dataset.entries.size()) {
      throw splat::Error((o.out / kCheckpointFile).string() + ": holds " + std::to_string(first) + " frames, " +
                         input.string() + " has " + std::to_string(dataset.entries.size()));
    }
    remove_stale_temporaries(o.out);
    outputs_owner = std::make_unique<RunOutputs>(o.out, input.string(), *rasterizer, plan.checkpoint->run);
    if (outputs_owner->records().size() != first) {
      throw splat::Error((o.out / kCheckpointFile).string() + ": the run recorded " +
                         std::to_string(outputs_owner->records().size()) + " frames, the SLAM state " + std::to_string(first));
    }
    slam.restore(std::move(plan.checkpoint->slam), load);
    plan.checkpoint.reset();
    std::fprintf(stderr, "resuming at frame %zu of %zu\n", first, dataset.entries.size());
  } else {
    outputs_owner = std::make_unique<RunOutputs>(o.out, input.string(), *rasterizer, o.overwrite);
    // What the run read, so that eval and --resume use the same camera, depth units and settings.
    outputs_owner->extra()["input"] = run_input_json(input, dataset, plan.dataset_options.max_frames, plan.test_every, config);
  }
  RunOutputs& outputs = *outputs_owner;
  const auto save_state = [&] { write_run_checkpoint(o.out / kCheckpointFile, {slam.state(), outputs.state()}); };
  // Ctrl-C or SIGTERM: stop taking frames (or end the sweep) and write complete outputs.
  const InterruptGuard interrupt;
  Progress progress("reconstruct", dataset.entries.size(), "frames");
  progress.resume_at(first);
  const std::size_t every = static_cast<std::size_t>(std::max(1, o.checkpoint_every));
  std::size_t loops_reported = slam.loop_events().size();
  FramePrefetch prefetch(load, first, dataset.entries.size());
  for (std::size_t i = first; i < dataset.entries.size() && !InterruptGuard::interrupted(); ++i) {
    const auto load_start = std::chrono::steady_clock::now();  // loading: the time spent waiting for it
    splat::RgbdFrame frame = prefetch.take(i);
    const double loading_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - load_start).count();
    const FrameRecord record = slam.process(std::move(frame), is_held_out(i, plan.test_every));
    if (!record.tracked) std::fprintf(stderr, "\nframe %zu: tracking failed (%s)\n", i, record.reason.c_str());
    const std::vector<LoopEvent> loops = slam.loop_events();
    for (; loops_reported < loops.size(); ++loops_reported) std::fprintf(stderr, "\n%s\n", describe(loops[loops_reported]).c_str());
    outputs.add(record, loading_ms);
    std::string moving;
    if (record.moving_share > 0) moving = ", " + std::to_string(std::lround(100 * record.moving_share)) + "% moving";
    progress.update(i + 1, std::to_string(record.gaussians) + " Gaussians, " + std::to_string(slam.keyframes()) + " keyframes" +
                               moving);
    if ((i + 1) % every == 0) {
      outputs.update_poses(slam.trajectory());
      const bool with_map = (i + 1) % (5 * every) == 0;
      outputs.checkpoint(*slam.map(), slam.keyframes(), with_map);
      if (with_map) save_state();
    }
  }
  progress.finish();
  // Where a resumed run continues: after the last frame taken (the sweep starts over).
  outputs.update_poses(slam.trajectory());
  save_state();
  const std::size_t refine_frames = slam.refine_frames().size();
  if (config.refine_passes > 0 && refine_frames > 0 && !InterruptGuard::interrupted()) {
    Progress refine_progress("refine", config.sweep_visits(refine_frames).total, "frame visits");
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
                                     {"ghosts", refined.ghosts}, {"visits", refined.visits}, {"stopped_early", refined.stopped},
                                     {"blurred_frames", refined.blurred},
                                     {"seconds", refine_progress.elapsed_seconds()}};
    std::fprintf(stderr, "refined the map: %zu visits over %zu frames in %.1f s, %zu Gaussians pruned (%zu ghosts), %zu frames' blur modelled\n",
                 refined.visits, refined.frames, refine_progress.elapsed_seconds(), refined.pruned, refined.ghosts, refined.blurred);
  }
  outputs.update_poses(slam.trajectory());  // keyframes moved by mapping carry their frames
  outputs.set_mapping(slam.mapping_totals(), slam.loop_events(), slam.mapping_on_device(), slam.mapping_overlapped());
  if (!InterruptGuard::interrupted()) {  // the map's classes, from the label images if there are any
    fuse_run_labels(dataset, slam.trajectory(), *slam.map(), *rasterizer, config.mapping.refine_resolution_factor, outputs);
  }
  const bool interrupted = InterruptGuard::interrupted();
  outputs.extra()["interrupted"] = interrupted;
  outputs.set_resumable(interrupted);
  outputs.set_stopping(interrupted);
  const std::string resume = "gslam reconstruct --resume --out " + o.out.string();
  if (interrupted) {
    outputs.extra()["resume"] = resume;
    std::fprintf(stderr, "interrupted: writing what was done (no keyframe renders)\n");
  }
  std::vector<StampedPose> truth;
  for (const auto& e : dataset.entries) {
    if (e.T_world_cam_truth) truth.push_back({e.timestamp, *e.T_world_cam_truth});
  }
  const std::shared_ptr<const splat::Gaussians> map = slam.map();
  outputs.finish(*map, slam.keyframes(), *rasterizer, dataset.intrinsics, truth);
  if (!interrupted) std::filesystem::remove(o.out / kCheckpointFile);  // nothing to resume
  const std::size_t frames = outputs.records().size();
  if (interrupted) {
    std::printf("interrupted after %zu of %zu frames%s; outputs so far in %s; continue with: %s\n", frames,
                dataset.entries.size(), frames == dataset.entries.size() ? " (in the final sweep)" : "", o.out.c_str(),
                resume.c_str());
    return 0;
  }
  std::printf("reconstructed %zu frames (%zu keyframes, %zu tracking failures) into %zu Gaussians at %.2f frames/s -> %s\n",
              frames, slam.keyframes(), outputs.failures(), map->size(),
              static_cast<double>(frames) / outputs.elapsed_seconds(), o.out.c_str());
  return 0;
}

}  // namespace app
