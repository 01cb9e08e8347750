// System tests: reconstruct sequences end to end and bound the trajectory error against
// ground truth.
#include <gtest/gtest.h>

#include <algorithm>

#include "datasets/dataset.h"
#include "evaluation/trajectory_errors.h"
#include "slam/slam_system.h"
#include "datasets/synthetic_sequence.h"
#include "splat/error.h"
#include "splat/losses.h"
#include "support/backends.h"
#include "support/synthetic_dataset.h"
#include "support/temp_dir.h"
#include "support/test_data.h"

namespace {

std::vector<app::StampedPose> track(splat::Rasterizer& rasterizer, const app::Dataset& dataset,
                                    std::vector<app::StampedPose>& truth, std::size_t& failures) {
  app::SlamSystem slam(rasterizer, app::SlamConfig{});
  std::vector<app::StampedPose> estimate;
  failures = 0;
  for (std::size_t i = 0; i < dataset.entries.size(); ++i) {
    const app::FrameRecord r = slam.process(dataset.load(i));
    failures += r.tracked ? 0 : 1;
    estimate.push_back({r.timestamp, r.T_world_cam});
    if (dataset.entries[i].T_world_cam_truth) truth.push_back({r.timestamp, *dataset.entries[i].T_world_cam_truth});
  }
  // The final estimate: mapping may have moved keyframes since their frames were tracked.
  const std::vector<Eigen::Isometry3d> poses = slam.trajectory();
  for (std::size_t i = 0; i < estimate.size(); ++i) estimate[i].T_world_cam = poses[i];
  return estimate;
}

// The bundled synthetic room, `frames` long, written under `dir`.
app::Dataset synthetic_dataset(const gslam::test::TempDir& dir, int frames) {
  app::SyntheticOptions o;
  o.frames = frames;
  return gslam::test::synthetic_dataset(dir / "seq", o);
}

std::vector<app::FrameRecord> process_all(app::SlamSystem& slam, const app::Dataset& dataset) {
  std::vector<app::FrameRecord> records;
  for (std::size_t i = 0; i < dataset.entries.size(); ++i) records.push_back(slam.process(dataset.load(i)));
  return records;
}

// The ATE of `poses` (one per record) against the dataset's ground truth.
double ate_of(const std::vector<Eigen::Isometry3d>& poses, const std::vector<app::FrameRecord>& records,
              const app::Dataset& dataset) {
  std::vector<app::StampedPose> estimate, truth;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    estimate.push_back({records[i].timestamp, poses[i]});
    truth.push_back({records[i].timestamp, *dataset.entries[i].T_world_cam_truth});
  }
  return app::evaluate_trajectory(estimate, truth).ate_rmse;
}

// Every frame of `dataset` processed with `config` (their records), then the trajectory after
// the final sweep.
struct Swept {
  std::vector<app::FrameRecord> records;
  std::vector<Eigen::Isometry3d> refined;
};
Swept process_and_sweep(const app::Dataset& dataset, const app::SlamConfig& config) {
  auto rasterizer = splat::make_cpu_rasterizer();
  app::SlamSystem slam(*rasterizer, config);
  Swept out{process_all(slam, dataset), {}};
  slam.refine_map([&](std::size_t i) { return dataset.load(i); });
  out.refined = slam.trajectory();
  return out;
}

app::TrajectoryErrors reconstruct(const app::Dataset& dataset, std::size_t& failures) {
  auto rasterizer = splat::make_cpu_rasterizer();
  std::vector<app::StampedPose> truth;
  const auto estimate = track(*rasterizer, dataset, truth, failures);
  return app::evaluate_trajectory(estimate, truth);
}

// Tracking and mapping run unchanged on the Vulkan backend and follow the same trajectory.
// 8 frames (4 keyframes): lavapipe takes ~5 s a frame here.
TEST(SlamSystem, VulkanAndCpuBackendsGiveTheSameTrajectoryWithinOneMillimetre) {
  GSLAM_REQUIRE_BACKEND(cpu, "cpu");
  GSLAM_REQUIRE_BACKEND(gpu, "vulkan");
  gslam::test::TempDir dir;
  const app::Dataset dataset = synthetic_dataset(dir, 8);
  std::vector<app::StampedPose> truth_cpu, truth_gpu;
  std::size_t failures_cpu = 0, failures_gpu = 0;
  const auto a = track(cpu, dataset, truth_cpu, failures_cpu);
  const auto b = track(gpu, dataset, truth_gpu, failures_gpu);
  EXPECT_EQ(failures_cpu, 0u);
  EXPECT_EQ(failures_gpu, 0u);
  ASSERT_EQ(a.size(), b.size());
  double worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double d = (a[i].T_world_cam.translation() - b[i].T_world_cam.translation()).norm();
    worst = std::max(worst, d);
    EXPECT_LT(d, 1e-3) << "frame " << i;
  }
  std::printf("cpu vs vulkan: largest position difference %.3f mm over %zu frames\n", worst * 1e3, a.size());
}

TEST(SlamSystem, SyntheticRoomTrajectoryWithinOneCentimetre) {
  gslam::test::TempDir dir;
  std::size_t failures = 0;
  const app::TrajectoryErrors e = reconstruct(synthetic_dataset(dir, 30), failures);
  std::printf("synthetic: ATE %.2f cm over %zu frames\n", e.ate_rmse * 100, e.matched);
  EXPECT_EQ(failures, 0u);
  EXPECT_LT(e.ate_rmse, 0.01);
}

// Mapping moves keyframe poses (MapperConfig::pose_*learning_rate > 0) but never the first,
// which defines the world frame; with both rates 0 (the default) every frame keeps its tracked
// pose until the final sweep (covisibility, which moves keyframes from the back end, off).
TEST(SlamSystem, MappingMovesKeyframesButNeverTheFirst) {
  gslam::test::TempDir dir;
  const app::Dataset dataset = synthetic_dataset(dir, 12);
  auto rasterizer = splat::make_cpu_rasterizer();
  for (const bool move : {true, false}) {
    app::SlamConfig config;
    config.loop_closure.covisible_keyframes = 0;  // the back end's corrections move keyframes too
    // The rates the render front end uses; the odometry's default keeps keyframes fixed.
    config.mapping.pose_learning_rate = move ? 2e-4 : 0;
    config.mapping.pose_rotation_learning_rate = move ? 5e-5 : 0;
    app::SlamSystem slam(*rasterizer, config);
    const std::vector<app::FrameRecord> records = process_all(slam, dataset);
    const std::vector<Eigen::Isometry3d> poses = slam.trajectory();
    ASSERT_EQ(poses.size(), records.size());
    EXPECT_TRUE(poses[0].isApprox(Eigen::Isometry3d::Identity(), 0)) << "the first keyframe moved";
    double largest = 0;
    for (std::size_t i = 0; i < poses.size(); ++i) {
      largest = std::max(largest, (poses[i].translation() - records[i].T_world_cam.translation()).norm());
    }
    std::printf("keyframes %s: frames moved up to %.3f mm after tracking\n", move ? "refined" : "fixed", largest * 1e3);
    if (move) {
      EXPECT_GT(largest, 1e-5);
    } else {
      EXPECT_LT(largest, 1e-9);
    }
  }
}

TEST(SlamSystem, RealTeddySequencePrefixTrajectoryWithinOneCentimetre) {
  GSLAM_REQUIRE_SHARED_DATA(root, "tum_rgbd_fr3_teddy_first200/rgbd_dataset_freiburg3_teddy");
  app::DatasetOptions options;
  options.max_frames = 40;
  std::size_t failures = 0;
  const app::TrajectoryErrors e = reconstruct(app::open_dataset(root, options), failures);
  std::printf("teddy first 40: ATE %.2f cm over %zu frames, %zu failures\n", e.ate_rmse * 100, e.matched, failures);
  EXPECT_LT(e.ate_rmse, 0.01);  // 0.47 cm with keyframe poses refined
}

// Re-tracking the refined frames against the final map (SlamConfig::relocalize_iterations)
// keeps the world frame where it is and the trajectory within a centimetre of the truth.
TEST(SlamSystem, RelocalizationAfterRefinementKeepsTheTrajectoryClose) {
  gslam::test::TempDir dir;
  const app::Dataset dataset = synthetic_dataset(dir, 10);
  app::SlamConfig config;
  config.refine_passes = 1;
  config.relocalize_iterations = 5;
  const auto [records, refined] = process_and_sweep(dataset, config);
  EXPECT_TRUE(refined[0].isApprox(records[0].T_world_cam, 0));
  const double ate = ate_of(refined, records, dataset);
  std::printf("synthetic, %zu frames, relocalized: ATE %.3f cm\n", records.size(), 100 * ate);
  EXPECT_LT(ate, 0.01);
}

}  // namespace

namespace {

double mean_psnr(splat::Rasterizer& rasterizer, const app::SlamSystem& slam, const app::Dataset& dataset,
                 const std::vector<app::FrameRecord>& records) {
  double sum = 0;
  for (std::size_t i = 0; i < records.size(); ++i) {
    const splat::RgbdFrame frame = dataset.load(i);
    const auto render = rasterizer.forward(*slam.map(), splat::posed(frame.camera, records[i].T_world_cam.inverse()),
                                           splat::images_only());
    sum += splat::psnr(render.rgb, frame.rgb, 3);
  }
  return sum / static_cast<double>(records.size());
}

// Which frames the final sweep visits: the keyframes, or every frame tracked.
TEST(SlamSystem, RefinementVisitsKeyframesOrEveryTrackedFrame) {
  gslam::test::TempDir dir;
  const app::Dataset dataset = synthetic_dataset(dir, 6);
  auto rasterizer = splat::make_cpu_rasterizer({1});
  for (const bool all : {false, true}) {
    app::SlamConfig config;
    config.keyframe_every = 3;
    config.keyframe_translation = config.keyframe_rotation_deg = 1e3;  // keyframes by count alone
    config.mapping.iterations = 2;
    config.refine_all_frames = all;
    app::SlamSystem slam(*rasterizer, config);
    const std::vector<app::FrameRecord> records = process_all(slam, dataset);
    std::vector<std::size_t> expected;
    for (std::size_t i = 0; i < records.size(); ++i) {
      if (records[i].keyframe || (all && records[i].tracked)) expected.push_back(i);
    }
    EXPECT_EQ(slam.refine_frames(), expected) << "refine_all_frames " << all;
    EXPECT_EQ(slam.refine_frames().size(), all ? records.size() : 2u) << "frames 0 and 3 are the keyframes";
  }
}

// The final sweep over every tracked frame (reloaded from the dataset) undoes what later windows
// did to regions earlier keyframes saw: the whole sequence renders better afterwards.
TEST(SlamSystem, FinalRefinementRaisesRenderQualityOverTheSequence) {
  gslam::test::TempDir dir;
  const app::Dataset dataset = synthetic_dataset(dir, 20);
  auto rasterizer = splat::make_cpu_rasterizer();
  const app::SlamConfig config;
  ASSERT_GT(config.refine_passes, 0);
  app::SlamSystem slam(*rasterizer, config);
  std::vector<app::FrameRecord> records = process_all(slam, dataset);
  const double before = mean_psnr(*rasterizer, slam, dataset, records);
  std::size_t visits = 0, total = 0;
  for (std::size_t i = 0; i < records.size(); ++i) records[i].T_world_cam = slam.trajectory()[i];
  const app::SlamSystem::Refinement refinement =
      slam.refine_map([&](std::size_t i) { return dataset.load(i); },
                      [&](std::size_t done, std::size_t all) {
                        visits = done;
                        total = all;
                      });
  const std::vector<Eigen::Isometry3d> refined = slam.trajectory();
  ASSERT_EQ(refined.size(), records.size());
  EXPECT_EQ(refinement.visits, total);
  // By default the sweep moves the map alone: every frame stays where tracking put it.
  ASSERT_EQ(config.mapping.refine_pose_learning_rate, 0);
  for (std::size_t i = 0; i < records.size(); ++i) EXPECT_TRUE(refined[i].isApprox(records[i].T_world_cam, 1e-12)) << i;
  ASSERT_TRUE(config.refine_all_frames);
  EXPECT_EQ(slam.refine_frames().size(), records.size()) << "every frame was tracked";
  EXPECT_EQ(total, records.size() * static_cast<std::size_t>(config.refine_passes));
  EXPECT_EQ(visits, total);
  const double after = mean_psnr(*rasterizer, slam, dataset, records);
  std::printf("synthetic, %zu frames: mean PSNR %.2f -> %.2f dB after refinement\n", records.size(), before, after);
  EXPECT_GT(after, before + 0.5);
}

// With refine_pose_learning_rate > 0 the swept frames' poses move with the map, but the first,
// which is the world frame.
TEST(SlamSystem, FinalRefinementMovesPosesWhereAsked) {
  gslam::test::TempDir dir;
  const app::Dataset dataset = synthetic_dataset(dir, 6);
  app::SlamConfig config;
  config.refine_passes = 2;
  config.mapping.refine_pose_learning_rate = 2e-3;
  config.mapping.refine_pose_rotation_learning_rate = 5e-4;
  const auto [records, refined] = process_and_sweep(dataset, config);
  ASSERT_EQ(refined.size(), records.size());
  EXPECT_TRUE(refined[0].isApprox(records[0].T_world_cam, 0));
  for (std::size_t i = 1; i < refined.size(); ++i) {
    EXPECT_GT((refined[i].translation() - records[i].T_world_cam.translation()).norm(), 1e-5) << "frame " << i;
  }
}

// The sweep keeps frames in memory within refine_cache_mib: each is loaded once instead of once
// per pass (and twice more, before the passes and after the densifying one, where every frame
// counts the ghosts it sees), and the result is the same as reloading them.
TEST(SlamSystem, RefinementCacheLoadsEachFrameOnceAndChangesNothing) {
  gslam::test::TempDir dir;
  const app::Dataset dataset = synthetic_dataset(dir, 4);
  auto rasterizer = splat::make_cpu_rasterizer({1});
  auto refine = [&](double cache_mib, std::size_t& loads) {
    app::SlamConfig config;
    config.refine_passes = 3;
    config.refine_cache_mib = cache_mib;
    app::SlamSystem slam(*rasterizer, config);
    process_all(slam, dataset);
    loads = 0;
    slam.refine_map([&](std::size_t i) {
      ++loads;
      return dataset.load(i);
    });
    return std::make_pair(slam.trajectory(), slam.map()->means);
  };
  std::size_t cached_loads = 0, reloads = 0;
  const auto cached = refine(app::SlamConfig{}.refine_cache_mib, cached_loads);
  const auto reloaded = refine(0, reloads);
  EXPECT_EQ(cached_loads, dataset.entries.size());
  EXPECT_EQ(reloads, (2 + 3) * dataset.entries.size());
  ASSERT_EQ(cached.first.size(), reloaded.first.size());
  for (std::size_t i = 0; i < cached.first.size(); ++i) EXPECT_TRUE(cached.first[i].isApprox(reloaded.first[i], 0)) << i;
  EXPECT_EQ(cached.second, reloaded.second);
}

// refine_max_visits bounds the sweep: the densifying pass visits every frame, and the visits left
// go round the frames so that none is visited twice before the others (frames reloaded on every
// visit show which were visited).
TEST(SlamSystem, CappedSweepVisitsTheFramesEvenly) {
  gslam::test::TempDir dir;
  const app::Dataset dataset = synthetic_dataset(dir, 5);
  auto rasterizer = splat::make_cpu_rasterizer({1});
  app::SlamConfig config;
  config.refine_passes = 4;
  config.refine_densify_passes = 1;
  config.refine_max_visits = 8;
  config.refine_cache_mib = 0;
  ASSERT_EQ(config.sweep_visits(5).densifying, 5u);
  ASSERT_EQ(config.sweep_visits(5).total, 8u);
  app::SlamSystem slam(*rasterizer, config);
  process_all(slam, dataset);
  std::vector<int> loads(dataset.entries.size(), 0);
  std::size_t reported_total = 0;
  const app::SlamSystem::Refinement refinement = slam.refine_map(
      [&](std::size_t i) {
        ++loads.at(i);
        return dataset.load(i);
      },
      [&](std::size_t, std::size_t total) { reported_total = total; });
  EXPECT_EQ(refinement.visits, 8u);
  EXPECT_EQ(reported_total, 8u);
  // Each frame: two ghost counts, the densifying visit, and one later visit for three of them.
  EXPECT_EQ(std::count(loads.begin(), loads.end(), 4), 3);
  EXPECT_EQ(std::count(loads.begin(), loads.end(), 3), 2);
}

}  // namespace

namespace {

// The largest difference between the elements of two poses' matrices (a loop: GCC 12 warns
// falsely inside Eigen's AVX-512 reductions).
double largest_difference(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  double largest = 0;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) largest = std::max(largest, std::abs(a.matrix()(r, c) - b.matrix()(r, c)));
  }
  return largest;
}

// One system, both modes: driven with a thread for mapping, waiting for each keyframe to be
// mapped before the next frame (what a live camera slower than mapping gives), it tracks
// against the same maps as the sequential run and ends with the same poses, corrections of the
// keyframes included.
TEST(SlamSystem, ThreadedMappingThatKeepsUpGivesTheSequentialTrajectory) {
  gslam::test::TempDir dir;
  const app::Dataset dataset = synthetic_dataset(dir, 10);
  app::SlamConfig config;
  config.mapping.iterations = 10;
  config.mapping.pose_learning_rate = 2e-4;  // mapping moves keyframes: their frames must follow
  config.mapping.pose_rotation_learning_rate = 5e-5;
  auto rasterizer = splat::make_cpu_rasterizer({2});
  app::SlamSystem sequential(*rasterizer, config);
  const std::vector<app::FrameRecord> records = process_all(sequential, dataset);
  auto tracking = splat::make_cpu_rasterizer({2}), mapping = splat::make_cpu_rasterizer({2});
  app::SlamSystem threaded(*tracking, *mapping, config);
  for (std::size_t i = 0; i < dataset.entries.size(); ++i) {
    const app::FrameRecord r = threaded.process(dataset.load(i));
    EXPECT_EQ(r.keyframe, records[i].keyframe) << "frame " << i;
    threaded.wait_for_mapping();
  }
  threaded.finish();
  const std::vector<Eigen::Isometry3d> a = sequential.trajectory(), b = threaded.trajectory();
  ASSERT_EQ(a.size(), b.size());
  bool corrected = false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_LT(largest_difference(a[i], b[i]), 1e-12) << "frame " << i;
    corrected = corrected || largest_difference(b[i], records[i].T_world_cam) > 1e-9;
  }
  EXPECT_TRUE(corrected) << "mapping moved no keyframe: the threaded trajectory must carry its corrections";
  EXPECT_EQ(threaded.mapping_totals().keyframes_mapped, sequential.mapping_totals().keyframes_mapped);
  EXPECT_EQ(threaded.mapping_totals().keyframes_skipped, 0u);
  EXPECT_EQ(threaded.map()->means, sequential.map()->means);
  EXPECT_EQ(threaded.map()->opacity_logits, sequential.map()->opacity_logits);
}

// A sequential run mapping on the device optimizes each keyframe while the next frames are
// tracked, and gives what mapping in turn gives: the same keyframes and map size, the trajectory
// to a micrometre (the keyframes' poses come back from the mapper a few frames later), and the
// same result bit for bit on a second run (the portable reduction repeats itself).
TEST(SlamSystem, OverlappedDeviceMappingGivesTheInTurnResultEveryRun) {
  GSLAM_REQUIRE_BACKEND(gpu, "vulkan_portable");
  gslam::test::TempDir dir;
  app::SyntheticOptions o;
  o.frames = 6;
  o.width = 160, o.height = 120, o.focal = 130;
  const app::Dataset dataset = gslam::test::synthetic_dataset(dir / "seq", o);
  app::SlamConfig config;
  config.mapping.iterations = 5;
  struct Run {
    std::vector<app::FrameRecord> records;
    std::vector<Eigen::Isometry3d> trajectory;
    splat::Gaussians map;
    bool overlapped = false;
  };
  auto run = [&](bool overlap) {
    config.overlap_mapping = overlap;
    app::SlamSystem slam(gpu, config);
    Run r{process_all(slam, dataset), {}, {}, slam.mapping_overlapped()};
    slam.finish();
    r.trajectory = slam.trajectory();
    r.map = *slam.map();
    return r;
  };
  const Run in_turn = run(false), overlapped = run(true), again = run(true);
  EXPECT_FALSE(in_turn.overlapped);
  ASSERT_TRUE(overlapped.overlapped);
  std::size_t keyframes = 0;
  double worst = 0;
  for (std::size_t i = 0; i < dataset.entries.size(); ++i) {
    EXPECT_EQ(overlapped.records[i].keyframe, in_turn.records[i].keyframe) << "frame " << i;
    keyframes += overlapped.records[i].keyframe;
    worst = std::max(worst, largest_difference(overlapped.trajectory[i], in_turn.trajectory[i]));
    EXPECT_LT(largest_difference(overlapped.trajectory[i], in_turn.trajectory[i]), 1e-6) << "frame " << i;
    EXPECT_EQ(overlapped.trajectory[i].matrix(), again.trajectory[i].matrix()) << "frame " << i;
  }
  EXPECT_GE(keyframes, 3u) << "too few keyframes to overlap anything";
  std::printf("overlapped vs in turn: %zu keyframes, largest pose difference %.2g\n", keyframes, worst);
  EXPECT_EQ(overlapped.map.size(), in_turn.map.size());
  EXPECT_EQ(overlapped.map.means, again.map.means);
  EXPECT_EQ(overlapped.map.opacity_logits, again.map.opacity_logits);
}

// A mapper that cannot keep up skips keyframes (the newest one waiting wins) and tracking goes on.
TEST(SlamSystem, ThreadedMappingSkipsKeyframesItCannotKeepUpWith) {
  gslam::test::TempDir dir;
  const app::Dataset dataset = synthetic_dataset(dir, 12);
  app::SlamConfig config;
  config.keyframe_every = 1;
  config.mapping.iterations = 200;  // far slower than tracking
  auto tracking = splat::make_cpu_rasterizer({1}), mapping = splat::make_cpu_rasterizer({1});
  app::SlamSystem threaded(*tracking, *mapping, config);
  for (std::size_t i = 0; i < dataset.entries.size(); ++i) threaded.process(dataset.load(i));
  threaded.finish();
  const app::MappingTotals t = threaded.mapping_totals();
  EXPECT_EQ(t.keyframes_mapped + t.keyframes_skipped, threaded.keyframes());
  EXPECT_GT(t.keyframes_skipped, 0u);
  EXPECT_EQ(threaded.trajectory().size(), dataset.entries.size());
}

TEST(SlamSystem, ThreadedModeRefusesTheTrackingRasterizerForMapping) {
  auto rasterizer = splat::make_cpu_rasterizer({1});
  EXPECT_THROW(
      {
        try {
          app::SlamSystem(*rasterizer, *rasterizer, app::SlamConfig{});
        } catch (const splat::Error& e) {
          EXPECT_NE(std::string(e.what()).find("rasterizer of its own"), std::string::npos) << e.what();
          throw;
        }
      },
      splat::Error);
}

}  // namespace

namespace {

// Measured 0.59 cm with the odometry front end (the test prints it; 0.80 before the depth
// weight followed the predicted blur, 0.97 before points at depth edges were left out). The
// bound allows for other compilers' rounding and stays far below what a lost or drifting frame
// costs (centimetres to metres).
constexpr double kHardMotionAteBound = 0.015;

// The generator's hard case (tracking/ issue: fast rotation peaking at 2.2 rad/s, motion blur,
// Kinect-like depth noise and holes), tracked by the default front end with the map built as
// usual: no frame lost, and the trajectory within the bound below of the exact truth.
TEST(SlamSystem, HardMotionSyntheticSequenceTracksEveryFrame) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o = app::SyntheticOptions::hard_motion();
  o.frames = 60;  // two seconds: three shake periods, six rotation-rate peaks
  const app::Dataset dataset = gslam::test::synthetic_dataset(dir / "hard", o);
  double peak_rate = 0;
  for (std::size_t i = 1; i < dataset.entries.size(); ++i) {
    const Eigen::Isometry3d step = dataset.entries[i - 1].T_world_cam_truth->inverse() * *dataset.entries[i].T_world_cam_truth;
    peak_rate = std::max(peak_rate, Eigen::AngleAxisd(step.linear()).angle() * o.fps);
  }
  ASSERT_GE(peak_rate, 2.0) << "the sequence must rotate at 2 rad/s or more";
  std::size_t failures = 0;
  const app::TrajectoryErrors e = reconstruct(dataset, failures);
  std::printf("hard motion: peak %.2f rad/s, ATE %.2f cm over %zu frames, %zu failures\n", peak_rate, e.ate_rmse * 100,
              e.matched, failures);
  EXPECT_EQ(failures, 0u);
  EXPECT_LT(e.ate_rmse, kHardMotionAteBound);
}

}  // namespace

namespace {

// The ATE of a run over the whole sequence with loop closure on or off, and the loops it
// verified. Light mapping, and keyframes every 15 cm or 10 degrees: the sanitized build runs
// these sequences too. `threaded`: as `live` runs, mapping (and so loop closure) on its own
// thread, waited for after each frame.
double ate_with_loop_closure(const app::Dataset& dataset, bool loop_closure, std::vector<app::LoopEvent>& events,
                             bool threaded = false) {
  app::SlamConfig config;
  config.loop_closure.enabled = loop_closure;
  config.mapping.iterations = 3;
  config.keyframe_translation = 0.15;
  config.keyframe_rotation_deg = 10;
  auto rasterizer = splat::make_cpu_rasterizer(), mapping_rasterizer = splat::make_cpu_rasterizer();
  std::unique_ptr<app::SlamSystem> system = threaded ? std::make_unique<app::SlamSystem>(*rasterizer, *mapping_rasterizer, config)
                                                     : std::make_unique<app::SlamSystem>(*rasterizer, config);
  app::SlamSystem& slam = *system;
  std::vector<app::FrameRecord> records;
  for (std::size_t i = 0; i < dataset.entries.size(); ++i) {
    records.push_back(slam.process(dataset.load(i)));
    slam.wait_for_mapping();
  }
  slam.finish();
  events = slam.loop_events();
  return ate_of(slam.trajectory(), records, dataset);  // keyframes moved since tracking included
}

// Two laps of the room with a noisy, blurred camera (1.3 rad/s, 1/60 s exposure, 8 mm depth
// noise at 1 m, holes): odometry drifts; the second lap revisits the first, place recognition
// finds it, dense alignment measures it, and the pose graph removes the drift.
TEST(SlamSystem, TwoLapsLoopClosureRemovesOdometryDrift) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o;
  o.frames = 300;
  o.laps = 2;
  o.exposure = 1.0 / 60;
  o.blur_samples = 4;
  o.depth_noise = 0.008;
  o.depth_holes = 0.05;
  const app::Dataset dataset = gslam::test::synthetic_dataset(dir / "laps", o);
  // With loop closure as `live` runs it: on the mapping thread.
  std::vector<app::LoopEvent> none, loops;
  const double odometry = ate_with_loop_closure(dataset, false, none);
  const double closed = ate_with_loop_closure(dataset, true, loops, true);
  std::size_t accepted = 0;
  for (const auto& e : loops) accepted += e.accepted;
  std::printf("two laps: ATE %.2f cm without loop closure, %.2f cm with (%zu loops accepted of %zu)\n", 100 * odometry,
              100 * closed, accepted, loops.size());
  EXPECT_GT(accepted, 0u);
  EXPECT_LT(closed, odometry / 5);
}

}  // namespace

namespace {

// Covisibility: a fast, blurred, hole-ridden camera (3 rad/s, 1/30 s exposure, 15% holes,
// the benchmark's blur_and_holes case) drifts when each keyframe hangs on its reference alone;
// aligning every keyframe also against the recent ones, and solving the graph with those edges,
// removes much of it.
TEST(SlamSystem, CovisibleKeyframesReduceDriftUnderBlur) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o = app::SyntheticOptions::hard_motion();
  o.frames = 120;
  o.shake_peak_rate = 3.0;
  o.exposure = 1.0 / 30;
  o.depth_holes = 0.15;
  const app::Dataset dataset = gslam::test::synthetic_dataset(dir / "blur", o);
  const auto ate = [&](int covisible, app::MappingTotals& totals) {
    app::SlamConfig config;
    config.loop_closure.covisible_keyframes = covisible;
    config.mapping.iterations = 3;  // the odometry does not read the map: light mapping suffices
    auto rasterizer = splat::make_cpu_rasterizer();
    app::SlamSystem slam(*rasterizer, config);
    const std::vector<app::FrameRecord> records = process_all(slam, dataset);
    totals = slam.mapping_totals();
    return ate_of(slam.trajectory(), records, dataset);  // keyframes moved since tracking included
  };
  app::MappingTotals chained, linked;
  const double alone = ate(0, chained), covisible = ate(4, linked);
  std::printf("blur and holes: ATE %.3f cm chained, %.3f cm with covisibility (%zu edges, %zu left out)\n", 100 * alone,
              100 * covisible, linked.covisible_edges, linked.covisible_rejected);
  EXPECT_EQ(chained.covisible_edges, 0u);
  EXPECT_GT(linked.covisible_edges, 3 * linked.keyframes_mapped / 2) << "most keyframes link to several others";
  EXPECT_LT(covisible, 0.8 * alone);
}

// Unsynchronized cameras: each depth image taken up to 15 ms before or after its colour image
// (as Kinect v1 in TUM's fr1/fr2), on a camera turning at up to 2.2 rad/s. Taken as if together,
// depth and colour disagree by up to 2 degrees and the odometry drifts by centimetres; with the
// depth moved to the colour's instant at the camera's velocity, it tracks within millimetres.
TEST(SlamSystem, UnsynchronizedDepthIsMovedToTheColoursInstant) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o = app::SyntheticOptions::hard_motion();
  o.frames = 100;
  o.depth_lag = 0.015;
  app::Dataset dataset = gslam::test::synthetic_dataset(dir / "lag", o);
  const auto ate = [&](const app::Dataset& d) {
    auto rasterizer = splat::make_cpu_rasterizer();
    app::SlamSystem slam(*rasterizer, app::SlamConfig{});
    const std::vector<app::FrameRecord> records = process_all(slam, d);
    return ate_of(slam.trajectory(), records, d);
  };
  double largest_offset = 0;
  for (const app::DatasetEntry& e : dataset.entries) largest_offset = std::max(largest_offset, std::abs(e.depth_offset));
  EXPECT_GT(largest_offset, 0.012) << "the depth.txt stamps carry the offsets";
  const double moved = ate(dataset);
  for (app::DatasetEntry& e : dataset.entries) e.depth_offset = 0;  // as if taken together
  const double together = ate(dataset);
  std::printf("depth 15 ms apart: ATE %.3f cm with the depth moved, %.3f cm without\n", 100 * moved, 100 * together);
  EXPECT_LT(moved, 0.5 * together);
  EXPECT_LT(moved, 0.005);
}

// A camera whose lens distorts (TUM's fr1 Kinect) tracks as well as a pinhole one once its frames
// are undistorted; taken for a pinhole camera, it drifts.
TEST(SlamSystem, LensDistortionIsUndistortedAsFramesLoad) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o;
  o.frames = 100;
  o.shake_peak_rate = 1.0;
  o.depth_noise = 0.0015;
  o.distortion = {0.262383, -0.953104, -0.005358, 0.002628, 1.163314};
  const app::Dataset undistorted = gslam::test::synthetic_dataset(dir / "lens", o);
  ASSERT_TRUE(undistorted.undistortion) << "intrinsics.txt states the distortion";
  app::DatasetOptions pinhole;
  pinhole.intrinsics = "260,260,160,120";  // the generator's camera without its lens
  const app::Dataset ignored = app::open_dataset(dir / "lens", pinhole);
  const auto ate = [&](const app::Dataset& d) {
    auto rasterizer = splat::make_cpu_rasterizer();
    app::SlamSystem slam(*rasterizer, app::SlamConfig{});
    const std::vector<app::FrameRecord> records = process_all(slam, d);
    return ate_of(slam.trajectory(), records, d);
  };
  const double with_lens = ate(undistorted), without = ate(ignored);
  std::printf("fr1 lens: ATE %.3f cm undistorted, %.3f cm taken for a pinhole\n", 100 * with_lens,
              100 * without);
  EXPECT_LT(with_lens, 0.002);
  EXPECT_LT(with_lens, 0.2 * without);
}

// A frame tracking cannot place (the view from the sequence's last frame, given frame 10's stamp)
// is lost, and reported where the camera's motion predicts it, not where the refused alignment
// ended; the next frame is tracked again.
TEST(SlamSystem, LostFrameIsPlacedWhereTheMotionPredicts) {
  gslam::test::TempDir dir;
  const app::Dataset dataset = synthetic_dataset(dir, 30);
  app::SlamConfig config;
  config.loop_closure.enabled = false;  // no relocalization: the frame stays lost
  config.mapping.iterations = 3;
  auto rasterizer = splat::make_cpu_rasterizer();
  app::SlamSystem slam(*rasterizer, config);
  std::vector<app::FrameRecord> records;
  for (std::size_t i = 0; i < 12; ++i) {
    splat::RgbdFrame frame = dataset.load(i == 10 ? 29 : i);
    frame.timestamp = dataset.entries[i].timestamp;
    records.push_back(slam.process(frame));
  }
  ASSERT_FALSE(records[10].tracked) << "the far view must not align";
  // Poses are in the first camera's frame.
  const Eigen::Isometry3d truth =
      dataset.entries[0].T_world_cam_truth->inverse() * *dataset.entries[10].T_world_cam_truth;
  const double error = (records[10].T_world_cam.translation() - truth.translation()).norm();
  std::printf("lost frame (%s): %.2f mm from where the camera was\n", records[10].reason.c_str(),
              1000 * error);
  EXPECT_LT(error, 0.005) << "the lost frame is " << 1000 * error
                          << " mm from the camera's true position";
  EXPECT_TRUE(records[11].tracked) << "the frame after the lost one: " << records[11].reason;
}

// A kidnapped camera: at frame 60 it is carried back to where it was at frame 15. Tracking
// loses it, relocalization finds it among the keyframes within 10 frames, and the rest of the
// run continues in the same map, at the true poses.
TEST(SlamSystem, KidnappedCameraIsRelocalizedInTheSameMap) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o;
  o.frames = 90;
  o.kidnap_frame = 60;
  o.kidnap_to = 15;
  const app::Dataset dataset = gslam::test::synthetic_dataset(dir / "kidnap", o);
  app::SlamConfig config;
  config.mapping.iterations = 6;
  auto rasterizer = splat::make_cpu_rasterizer();
  app::SlamSystem slam(*rasterizer, config);
  std::vector<app::FrameRecord> records = process_all(slam, dataset);
  std::size_t relocalized_at = 0;
  for (std::size_t i = 60; i < 70 && relocalized_at == 0; ++i) relocalized_at = records[i].relocalized ? i : 0;
  ASSERT_GT(relocalized_at, 0u) << "not relocalized within 10 frames of the jump";
  const std::vector<Eigen::Isometry3d> poses = slam.trajectory();
  std::vector<app::StampedPose> estimate, truth;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    if (i >= 60 && i < relocalized_at) continue;  // lost: no pose to score
    estimate.push_back({records[i].timestamp, poses[i]});
    truth.push_back({records[i].timestamp, *dataset.entries[i].T_world_cam_truth});
    if (i >= relocalized_at) {
      EXPECT_TRUE(records[i].tracked) << "frame " << i;
    }
  }
  const app::TrajectoryErrors errors = app::evaluate_trajectory(estimate, truth);
  std::printf("kidnapped at 60, relocalized at frame %zu; ATE %.2f cm\n", relocalized_at, 100 * errors.ate_rmse);
  EXPECT_LT(errors.ate_rmse, 0.01);
}

}  // namespace

namespace {

// Two identical rooms walked through one after the other: the second looks like the first, so
// place recognition and dense alignment agree on a "loop" 5 m long, which the drift budget
// rejects; the trajectory is the one without loop closure.
TEST(SlamSystem, LookAlikePlaceIsNotTakenForALoop) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o;
  o.frames = 120;
  o.twin_rooms = true;
  const app::Dataset dataset = gslam::test::synthetic_dataset(dir / "twins", o);
  std::vector<app::LoopEvent> none, events;
  const double without = ate_with_loop_closure(dataset, false, none);
  const double with = ate_with_loop_closure(dataset, true, events);
  std::size_t accepted = 0;
  for (const auto& e : events) accepted += e.accepted;
  std::printf("twin rooms: %zu look-alike loops found, %zu accepted; ATE %.2f cm without loop closure, %.2f cm with\n",
              events.size(), accepted, 100 * without, 100 * with);
  EXPECT_GT(events.size(), 0u) << "the second room must look like the first to place recognition";
  EXPECT_EQ(accepted, 0u);
  EXPECT_NEAR(with, without, 1e-4);
}

}  // namespace
