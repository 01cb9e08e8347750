// Checkpoints: a run stopped, written to a checkpoint, read back and continued ends exactly as
// the run that never stopped; hostile checkpoint files get one-line errors.
#include "io/run_checkpoint.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <memory>

#include "datasets/dataset.h"
#include "datasets/synthetic_sequence.h"
#include "slam/slam_system.h"
#include "splat/vulkan_rasterizer.h"
#include "support/backends.h"
#include "support/expect_error.h"
#include "support/synthetic_dataset.h"
#include "support/temp_dir.h"

namespace {

// Small enough to run in a second, long enough that keyframes leave the mapper's store, the
// tracker's references and covisibility's recent keyframes, and that mapping moves keyframes
// (its pose Adam state matters).
app::SlamConfig checkpoint_config() {
  app::SlamConfig config;
  config.mapping.iterations = 6;
  config.mapping.max_keyframes = 3;
  config.mapping.pose_learning_rate = 2e-4;
  config.mapping.pose_rotation_learning_rate = 5e-5;
  config.keyframe_every = 2;
  config.refine_passes = 2;
  // Covisibility's recent keyframes are part of the state; a blur scale of 0 links every keyframe.
  config.loop_closure.covisible_keyframes = 2;
  config.odometry.blur_scale_px = 0;
  return config;
}

struct SystemRun {
  std::vector<Eigen::Isometry3d> trajectory;
  splat::Gaussians map;
  bool overlapped = false;  // SlamSystem::mapping_overlapped()
  std::size_t frames_moving = 0;  // frames with moving objects left out of mapping
  // What the checkpoint carried of the moving regions (nothing: not stopped): the last frame's
  // labels, and the label sets of tracking's references and covisibility's keyframes.
  bool moving_carried = false;
  std::size_t reference_labels = 0, covisible_labels = 0;
};

std::size_t non_empty(const std::vector<std::vector<uint8_t>>& sets) {
  return static_cast<std::size_t>(
      std::count_if(sets.begin(), sets.end(), [](const auto& l) { return !l.empty(); }));
}

using MakeRasterizer = std::function<std::unique_ptr<splat::Rasterizer>()>;
std::unique_ptr<splat::Rasterizer> cpu_rasterizer() { return splat::make_cpu_rasterizer({2}); }

// Processes frames [0, stop), checkpoints through `file`, continues in a new system (and a new
// rasterizer) from [stop, end), then sweeps. stop = end: never checkpointed.
SystemRun run(const app::Dataset& dataset, std::size_t stop, const std::filesystem::path& file,
              const MakeRasterizer& make_rasterizer = cpu_rasterizer) {
  const auto load = [&](std::size_t i) { return dataset.load(i); };
  const app::SlamConfig config = checkpoint_config();
  // Both made before the system, so that they outlive it (its resident map is the device's).
  auto first_rasterizer = make_rasterizer(), second_rasterizer = make_rasterizer();
  auto slam = std::make_unique<app::SlamSystem>(*first_rasterizer, config);
  for (std::size_t i = 0; i < stop; ++i) slam->process(load(i));
  SystemRun result;
  if (stop < dataset.entries.size()) {
    const app::SlamSystem::State state = slam->state();
    result.moving_carried = !state.tracker.moving.empty();
    result.reference_labels = non_empty(state.tracker.reference_labels);
    result.covisible_labels = non_empty(state.back_end.covisible_labels);
    // Overlapped, the newest keyframe is still being optimized: the checkpoint carries it.
    EXPECT_EQ(state.unpublished.has_value(), slam->mapping_overlapped()) << "stopped at " << stop;
    app::write_run_checkpoint(file, {state, {{"note", "test"}}});
    slam = std::make_unique<app::SlamSystem>(*second_rasterizer, config);
    const app::RunCheckpoint read = app::read_run_checkpoint(file);
    EXPECT_EQ(read.run.at("note"), "test");
    slam->restore(read.slam, load);
    for (std::size_t i = stop; i < dataset.entries.size(); ++i) slam->process(load(i));
  }
  std::size_t moved = 0;  // frames whose depth was moved to its colour's instant
  std::size_t frames_moving = 0;
  for (const auto& f : slam->state().frames) {
    moved += !f.T_colour_depth.isApprox(Eigen::Isometry3d::Identity());
    frames_moving += !f.moving.empty();
  }
  EXPECT_GT(moved, 3u);
  const bool overlapped = slam->mapping_overlapped();
  slam->refine_map(load);
  EXPECT_GT(slam->mapping_totals().covisible_edges, 0u);
  result.trajectory = slam->trajectory();
  result.map = *slam->map();
  result.overlapped = overlapped;
  result.frames_moving = frames_moving;
  return result;
}

struct Runs {
  SystemRun straight;
  std::vector<SystemRun> continued;  // one per stop
};

// Stopped at each of `stops`, the run ends bit for bit as the one that never stopped.
Runs expect_continued_runs_end_as_the_straight_one(
    const app::Dataset& dataset, const std::vector<std::size_t>& stops,
    const std::filesystem::path& file, const MakeRasterizer& make_rasterizer = cpu_rasterizer) {
  Runs runs{run(dataset, dataset.entries.size(), {}, make_rasterizer), {}};
  const SystemRun& straight = runs.straight;
  for (std::size_t stop : stops) {
    const SystemRun& resumed =
        runs.continued.emplace_back(run(dataset, stop, file, make_rasterizer));
    if (resumed.trajectory.size() != straight.trajectory.size()) {
      ADD_FAILURE() << "stopped at " << stop << ": " << resumed.trajectory.size() << " poses, " << straight.trajectory.size() << " straight";
      continue;
    }
    for (std::size_t i = 0; i < straight.trajectory.size(); ++i) {
      const Eigen::Matrix4d& a = straight.trajectory[i].matrix();
      const Eigen::Matrix4d& b = resumed.trajectory[i].matrix();
      EXPECT_TRUE(std::equal(a.data(), a.data() + 16, b.data())) << "stopped at " << stop << ", frame " << i;
    }
    EXPECT_EQ(resumed.map.means, straight.map.means) << "stopped at " << stop;
    EXPECT_EQ(resumed.map.sh, straight.map.sh) << "stopped at " << stop;
    EXPECT_EQ(resumed.map.opacity_logits, straight.map.opacity_logits) << "stopped at " << stop;
  }
  return runs;
}

TEST(RunCheckpoint, ContinuedRunEndsExactlyAsTheRunThatNeverStopped) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o;
  o.frames = 14;
  o.shake_peak_rate = 1.0;
  o.depth_lag = 0.012;  // depth moved to the colour's instant: the checkpoint carries how
  const app::Dataset dataset = gslam::test::synthetic_dataset(dir / "seq", o);
  EXPECT_FALSE(
      expect_continued_runs_end_as_the_straight_one(dataset, {1u, 6u, 11u}, dir / "checkpoint.bin")
          .straight.overlapped);
}

// A person walking through the view: tracking leaves the regions it found moving out of the
// next frame's first alignment and out of its reference keyframes, and the checkpoint carries
// both, so that a continued run finds and leaves out the same regions.
TEST(RunCheckpoint, RunWithMovingObjectsContinuesExactlyAsTheRunThatNeverStopped) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o;
  o.frames = 60;  // the person walks in from 0.3 s
  o.width = 160, o.height = 120, o.focal = 130;
  o.movers = true;
  o.depth_lag = 0.012;
  const app::Dataset dataset = gslam::test::synthetic_dataset(dir / "seq", o);
  const Runs runs =
      expect_continued_runs_end_as_the_straight_one(dataset, {40u, 50u}, dir / "checkpoint.bin");
  EXPECT_GE(runs.straight.frames_moving, 10u);
  // Each of the three was carried by some checkpoint (the person is found near every stop).
  std::size_t moving = 0, references = 0, covisible = 0;
  for (const SystemRun& continued : runs.continued) {
    moving += continued.moving_carried;
    references += continued.reference_labels;
    covisible += continued.covisible_labels;
  }
  EXPECT_GE(moving, 1u);
  EXPECT_GE(references, 1u);
  EXPECT_GE(covisible, 1u);
}

// Mapping on the device overlaps tracking: a checkpoint taken while a keyframe is optimized
// carries it unpublished, and the continued run publishes it where the straight run does (the
// portable reduction, which repeats itself bit for bit).
TEST(RunCheckpoint, OverlappedDeviceMappingContinuesExactlyAsTheRunThatNeverStopped) {
  GSLAM_REQUIRE_BACKEND(gpu, "vulkan_portable");
  (void)gpu;  // there is a device: the runs make rasterizers of their own, as a resumed run does
  gslam::test::TempDir dir;
  app::SyntheticOptions o;
  o.frames = 8;
  o.width = 160, o.height = 120, o.focal = 130;
  o.shake_peak_rate = 1.0;
  o.depth_lag = 0.012;
  const app::Dataset dataset = gslam::test::synthetic_dataset(dir / "seq", o);
  const MakeRasterizer portable = [] {
    splat::VulkanOptions options;
    options.float_atomics = false;
    return splat::make_vulkan_rasterizer(options);
  };
  EXPECT_TRUE(
      expect_continued_runs_end_as_the_straight_one(dataset, {3u}, dir / "checkpoint.bin", portable)
          .straight.overlapped);
}

// Loop closure's memory: confirmed loops keep their wider budget in the graph, and loops waiting
// for a confirming detection are still waiting after a resume.
TEST(RunCheckpoint, KeepsConfirmedLoopsAndTheLoopsWaitingForConfirmation) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o;
  o.frames = 4;
  const app::Dataset dataset = gslam::test::synthetic_dataset(dir / "seq", o);
  auto rasterizer = splat::make_cpu_rasterizer({2});
  app::SlamSystem slam(*rasterizer, checkpoint_config());
  for (std::size_t i = 0; i < dataset.entries.size(); ++i) slam.process(dataset.load(i));
  app::SlamSystem::State state = slam.state();
  tracking::PoseGraphEdge loop;
  loop.i = 0, loop.j = 1, loop.loop = true, loop.confirmed = true;
  state.back_end.edges.push_back(loop);
  loop.confirmed = false;
  state.back_end.rejected_loops = {loop};
  state.loop_events.push_back({30, 2, 28, 0.19, 3.1, true, 25});
  app::write_run_checkpoint(dir / "loops.bin", {state, {}});
  const app::SlamSystem::State back = app::read_run_checkpoint(dir / "loops.bin").slam;
  ASSERT_EQ(back.back_end.edges.size(), state.back_end.edges.size());
  EXPECT_TRUE(back.back_end.edges.back().confirmed);
  EXPECT_FALSE(back.back_end.edges.front().confirmed);
  ASSERT_EQ(back.back_end.rejected_loops.size(), 1u);
  EXPECT_TRUE(back.back_end.rejected_loops[0].loop);
  EXPECT_FALSE(back.back_end.rejected_loops[0].confirmed);
  ASSERT_FALSE(back.loop_events.empty());
  EXPECT_EQ(back.loop_events.back().confirms_frame, std::optional<std::size_t>(25));
}

TEST(RunCheckpoint, HostileFilesGiveOneLineErrors) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o;
  o.frames = 4;
  const app::Dataset dataset = gslam::test::synthetic_dataset(dir / "seq", o);
  auto rasterizer = splat::make_cpu_rasterizer({2});
  app::SlamSystem slam(*rasterizer, checkpoint_config());
  for (std::size_t i = 0; i < dataset.entries.size(); ++i) slam.process(dataset.load(i));
  const auto good = dir / "good.bin";
  app::write_run_checkpoint(good, {slam.state(), {}});
  const std::string bytes = gslam::test::read_text(good);
  auto write = [&](const std::string& name, const std::string& content) {
    gslam::test::write_text(dir / name, content);
    return dir / name;
  };
  GSLAM_EXPECT_ERROR(app::read_run_checkpoint(dir / "missing.bin"), "missing.bin", "cannot open");
  GSLAM_EXPECT_ERROR(app::read_run_checkpoint(write("magic.bin", "PLY\n" + bytes)), "magic.bin", "not a gslam checkpoint");
  GSLAM_EXPECT_ERROR(app::read_run_checkpoint(write("short.bin", bytes.substr(0, bytes.size() - 7))), "short.bin", "truncated");
  GSLAM_EXPECT_ERROR(app::read_run_checkpoint(write("long.bin", bytes + "x")), "long.bin", "1 bytes after");
  // A header length, then an array length, claiming far more than the file holds.
  std::string huge_header = bytes;
  const std::size_t magic = std::string("gslam checkpoint 2\n").size();
  huge_header[magic + 6] = '\x7f';
  GSLAM_EXPECT_ERROR(app::read_run_checkpoint(write("header.bin", huge_header)), "header.bin", "truncated");
  std::uint64_t header_length = 0;
  std::memcpy(&header_length, bytes.data() + magic, 8);
  std::string huge_array = bytes;
  huge_array[magic + 8 + header_length + 6] = '\x7f';
  GSLAM_EXPECT_ERROR(app::read_run_checkpoint(write("array.bin", huge_array)), "array.bin", "array 0", "claims");
  // Valid framing around a header that is not what a checkpoint holds.
  std::string wrong = bytes;
  const std::size_t frames = wrong.find("\"frames\"", magic + 8);
  ASSERT_NE(frames, std::string::npos);
  wrong.replace(frames, 8, "\"framez\"");
  GSLAM_EXPECT_ERROR(app::read_run_checkpoint(write("fields.bin", wrong)), "fields.bin", "malformed", "frames");
  // The frames' moving masks (what the final sweep leaves out) read back exactly; runs that do
  // not cover their mask are refused.
  app::SlamSystem::State state = slam.state();
  ASSERT_GE(state.frames.size(), 2u);
  state.frames[1].moving = {4, 3, 2, {5, 3, 4}};
  app::write_run_checkpoint(dir / "moving.bin", {state, {}});
  const app::MovingMask back = app::read_run_checkpoint(dir / "moving.bin").slam.frames[1].moving;
  EXPECT_EQ(back.width, 4);
  EXPECT_EQ(back.height, 3);
  EXPECT_EQ(back.factor, 2);
  EXPECT_EQ(back.runs, (std::vector<uint32_t>{5, 3, 4}));
  EXPECT_TRUE(app::read_run_checkpoint(dir / "moving.bin").slam.frames[0].moving.empty());
  // The keyframes' velocities (the rolling shutter's correction) read back exactly.
  ASSERT_FALSE(state.tracker.references.empty());
  state.tracker.reference_twists.assign(state.tracker.references.size(), {0.1, -0.2, 0.3, 1.5, -2.25, 0.125});
  state.back_end.covisible_twists.assign(state.back_end.covisible.size(), {-1, 2, -3, 4, -5, 6});
  app::write_run_checkpoint(dir / "twists.bin", {state, {}});
  const app::SlamSystem::State twists = app::read_run_checkpoint(dir / "twists.bin").slam;
  EXPECT_EQ(twists.tracker.reference_twists, state.tracker.reference_twists);
  EXPECT_EQ(twists.back_end.covisible_twists, state.back_end.covisible_twists);
  state.frames[1].moving.runs = {5, 3, 5};
  app::write_run_checkpoint(dir / "overrun.bin", {state, {}});
  GSLAM_EXPECT_ERROR(app::read_run_checkpoint(dir / "overrun.bin"), "overrun.bin",
                     "frame 1's moving mask: runs cover 13 pixels, the mask has 12");
  // Tracking's moving labels (the last frame's, its references' and covisibility's) read back
  // exactly; a value that is no label, or a run of a few bytes claiming more pixels than any
  // checkpoint holds, is refused before it is allocated.
  state = slam.state();
  ASSERT_FALSE(state.tracker.references.empty());
  ASSERT_FALSE(state.back_end.covisible.empty());
  state.tracker.moving = {0, 0, 1, 1, 1, 3, 0};
  state.tracker.reference_labels.assign(state.tracker.references.size(), {});
  state.tracker.reference_labels[0] = {2, 2, 0};
  state.back_end.covisible_labels.assign(state.back_end.covisible.size(), {});
  state.back_end.covisible_labels[0] = {3, 1};
  app::write_run_checkpoint(dir / "labels.bin", {state, {}});
  const app::SlamSystem::State labels_back = app::read_run_checkpoint(dir / "labels.bin").slam;
  EXPECT_EQ(labels_back.tracker.moving, state.tracker.moving);
  EXPECT_EQ(labels_back.tracker.reference_labels, state.tracker.reference_labels);
  EXPECT_EQ(labels_back.back_end.covisible_labels, state.back_end.covisible_labels);
  app::SlamSystem::State bad = state;
  bad.tracker.moving = {0, 9};
  app::write_run_checkpoint(dir / "label.bin", {bad, {}});
  GSLAM_EXPECT_ERROR(app::read_run_checkpoint(dir / "label.bin"), "label.bin",
                     "the last frame's moving labels: run 1 [9,1] is not a label");
  bad.tracker.moving.assign((16u << 20) + 1, 0);
  app::write_run_checkpoint(dir / "label_run.bin", {bad, {}});
  GSLAM_EXPECT_ERROR(app::read_run_checkpoint(dir / "label_run.bin"), "label_run.bin",
                     "reaches past the 16777216 label pixels");
  // Labels that do not fit their frame, or lists of different lengths, are refused by the system.
  const auto load = [&](std::size_t i) { return dataset.load(i); };
  auto refused = [&](const app::SlamSystem::State& s) {
    app::SlamSystem fresh(*rasterizer, checkpoint_config());
    fresh.restore(s, load);
  };
  bad = labels_back;
  bad.tracker.reference_labels.assign(state.tracker.references.size(), {});
  GSLAM_EXPECT_ERROR(refused(bad), "the last frame's moving labels: 7 moving labels do not fit");
  bad.tracker.moving.clear();
  bad.tracker.reference_labels = labels_back.tracker.reference_labels;
  GSLAM_EXPECT_ERROR(refused(bad), "tracking's references, keyframe", "3 moving labels do not fit");
  bad.tracker.reference_labels.assign(state.tracker.references.size(), {});
  GSLAM_EXPECT_ERROR(refused(bad), "covisibility's keyframes, keyframe",
                     "2 moving labels do not fit");
  bad.back_end.covisible_labels.push_back({});
  GSLAM_EXPECT_ERROR(refused(bad), "covisibility's keyframes", "label sets");
  // A checkpoint from before the labels were kept (none of the three fields) continues with none.
  std::string old_bytes = gslam::test::read_text(good);
  // (The tracker's "moving", not a frame's: frames may carry moving masks of their own.)
  const std::size_t tracker = old_bytes.find("\"tracker\"", magic + 8);
  for (const std::string field : {"\"reference_labels\"", "\"covisible_labels\"", "\"moving\""}) {
    const std::size_t at = old_bytes.find(field, field == "\"moving\"" ? tracker : magic + 8);
    ASSERT_NE(at, std::string::npos) << field;
    old_bytes.replace(at + field.size() - 2, 1, "z");  // the same length: the framing still holds
  }
  const app::SlamSystem::State old = app::read_run_checkpoint(write("old.bin", old_bytes)).slam;
  EXPECT_TRUE(old.tracker.moving.empty());
  EXPECT_TRUE(old.tracker.reference_labels.empty());
  EXPECT_TRUE(old.back_end.covisible_labels.empty());
  app::SlamSystem continued(*rasterizer, checkpoint_config());
  continued.restore(old, load);
  EXPECT_EQ(continued.trajectory().size(), dataset.entries.size());
  // A state that reads but does not hold together is refused by the system, not followed.
  app::RunCheckpoint c = app::read_run_checkpoint(good);
  c.slam.keyframe_world.pop_back();
  app::SlamSystem fresh(*rasterizer, checkpoint_config());
  GSLAM_EXPECT_ERROR(fresh.restore(c.slam, [&](std::size_t i) { return dataset.load(i); }), "keyframe poses");
}

}  // namespace
