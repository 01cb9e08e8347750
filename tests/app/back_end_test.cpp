// The back end solves for a keyframe from the poses of the keyframes up to it: edges tracking
// added meanwhile to later keyframes (threaded or overlapped mapping) must not change what it
// finds, so that `live` gives what `reconstruct` gives.
#include <gtest/gtest.h>

#include <optional>
#include <vector>

#include "datasets/dataset.h"
#include "datasets/synthetic_sequence.h"
#include "slam/back_end.h"
#include "slam/frame_tracker.h"
#include "slam/slam_config.h"
#include "support/synthetic_dataset.h"
#include "support/temp_dir.h"

namespace {

Eigen::Matrix<double, 6, 6> odometry_information() {
  return Eigen::Matrix<double, 6, 6>::Identity() * 1e4;
}

// The chain of odometry edges between consecutive keyframes 0 .. poses.size() - 1.
void add_chain(app::BackEnd& back_end, const std::vector<Eigen::Isometry3d>& poses) {
  for (std::size_t k = 1; k < poses.size(); ++k)
    back_end.add_odometry_edge(k - 1, k, poses[k - 1].inverse() * poses[k], odometry_information());
}

Eigen::Isometry3d shifted(const Eigen::Isometry3d& pose, const Eigen::Vector3d& by) {
  Eigen::Isometry3d out = pose;
  out.translation() += by;
  return out;
}

void expect_same_poses(const std::vector<Eigen::Isometry3d>& a, const std::vector<Eigen::Isometry3d>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) EXPECT_EQ(a[k].matrix(), b[k].matrix()) << "keyframe " << k;
}

struct Sequence {
  gslam::test::TempDir dir;
  app::Dataset dataset;
  Sequence() {
    app::SyntheticOptions o;
    o.frames = 20;
    dataset = gslam::test::synthetic_dataset(dir / "seq", o);
  }
  Eigen::Isometry3d truth(std::size_t i) const { return *dataset.entries[i].T_world_cam_truth; }
  // Keyframes 0 .. loop_keyframe() - 1 on frames 0, 1, ...; then the loop keyframe, which sees
  // frame 0 again, placed 2 cm off by drift.
  static std::size_t loop_keyframe(const app::SlamConfig& config) {
    return static_cast<std::size_t>(config.loop_closure.min_separation) + 1;
  }
  std::vector<Eigen::Isometry3d> up_to_loop(const app::SlamConfig& config) const {
    std::vector<Eigen::Isometry3d> poses;
    for (std::size_t k = 0; k < loop_keyframe(config); ++k) poses.push_back(truth(k));
    poses.push_back(shifted(truth(0), {0.02, 0, 0}));
    return poses;
  }
};

TEST(BackEnd, LoopSolvedTheSameWhateverTrackingAddedSince) {
  const Sequence sequence;
  const app::SlamConfig config;
  const std::size_t loop_keyframe = Sequence::loop_keyframe(config);
  // Two more keyframes follow the loop's.
  const std::vector<Eigen::Isometry3d> up_to_loop = sequence.up_to_loop(config);
  std::vector<Eigen::Isometry3d> poses = up_to_loop;
  poses.push_back(shifted(sequence.truth(1), {0.02, 0, 0}));
  poses.push_back(shifted(sequence.truth(2), {0.02, 0, 0}));

  app::BackEnd in_turn(config), ahead(config);
  add_chain(in_turn, up_to_loop);
  add_chain(ahead, poses);  // tracking got two keyframes further before the loop's job ran
  for (std::size_t k = 0; k < loop_keyframe; ++k) {
    const splat::RgbdFrame frame = sequence.dataset.load(k);
    const std::vector<Eigen::Isometry3d> earlier(up_to_loop.begin(), up_to_loop.begin() + static_cast<long>(k) + 1);
    EXPECT_FALSE(in_turn.close_loop(frame, k, earlier)) << "keyframe " << k << ": nothing is old enough to close on";
    EXPECT_FALSE(ahead.close_loop(frame, k, earlier)) << "keyframe " << k;
  }
  const splat::RgbdFrame again = sequence.dataset.load(0);
  const std::optional<app::BackEnd::Loop> a = in_turn.close_loop(again, loop_keyframe, up_to_loop);
  const std::optional<app::BackEnd::Loop> b = ahead.close_loop(again, loop_keyframe, up_to_loop);
  ASSERT_TRUE(a && b) << "the view of keyframe 0 seen again closes no loop";
  ASSERT_TRUE(a->accepted);
  EXPECT_EQ(a->matched_keyframe, b->matched_keyframe);
  EXPECT_EQ(a->accepted, b->accepted);
  EXPECT_NEAR(a->drift_m, 0.02, 0.005);
  ASSERT_EQ(a->solved.size(), up_to_loop.size());
  expect_same_poses(a->solved, b->solved);
  // The loop pulled the drifted keyframe most of the way back onto keyframe 0's view.
  EXPECT_LT((a->solved.back().translation() - sequence.truth(0).translation()).norm(), 0.01);
}

TEST(BackEnd, CovisibleSolveTheSameWhateverTrackingAddedSince) {
  const Sequence sequence;
  app::SlamConfig config;
  const std::size_t keyframes = 5, ahead_by = 2;
  std::vector<Eigen::Isometry3d> poses;
  for (std::size_t k = 0; k < keyframes + ahead_by; ++k)
    poses.push_back(shifted(sequence.truth(2 * k), {0.002 * static_cast<double>(k), 0, 0}));  // drifting
  const std::vector<Eigen::Isometry3d> mapped(poses.begin(), poses.begin() + static_cast<long>(keyframes));
  app::BackEnd in_turn(config), ahead(config);
  add_chain(in_turn, mapped);
  add_chain(ahead, poses);
  std::size_t edges = 0;
  for (std::size_t k = 0; k < keyframes; ++k) {
    app::FrameTracker::PreparedKeyframe prepared;
    prepared.frame = app::prepare_odometry_frame(sequence.dataset.load(2 * k), {}, config);
    prepared.keyframe = k;
    prepared.angular_rate = 10;  // blurred: covisibility links only such keyframes
    const std::vector<Eigen::Isometry3d> up_to(mapped.begin(), mapped.begin() + static_cast<long>(k) + 1);
    const app::BackEnd::Linked a = in_turn.link_covisible(prepared, config.odometry, up_to);
    const app::BackEnd::Linked b = ahead.link_covisible(prepared, config.odometry, up_to);
    EXPECT_EQ(a.edges, b.edges) << "keyframe " << k;
    expect_same_poses(a.solved, b.solved);
    edges += a.edges;
  }
  EXPECT_GT(edges, 0u) << "no covisible edge was added: the test compares nothing";
}

}  // namespace

namespace {

// A resumed run's back end rebuilds its places from the keyframes as mapping had them, moving
// regions ignored as close_loop() saw them: it then closes the same loop as the run that never
// stopped (the places' thumbnails carry the frames' ignored pixels into their dense alignment).
TEST(BackEnd, RestoredPlacesCloseTheLoopTheRunThatNeverStoppedCloses) {
  const Sequence sequence;
  const app::SlamConfig config;
  const std::size_t loop_keyframe = Sequence::loop_keyframe(config);
  const std::vector<Eigen::Isometry3d> poses = sequence.up_to_loop(config);
  // The keyframes as mapping has them: a moving region over the left third of each.
  const auto mapped_keyframe = [&](std::size_t k) {
    splat::RgbdFrame frame = sequence.dataset.load(k);
    frame.ignore.assign(frame.depth.size(), 0);
    for (int y = 0; y < frame.height(); ++y)
      for (int x = 0; x < frame.width() / 3; ++x) frame.ignore[static_cast<std::size_t>(y) * frame.width() + x] = 2;
    return frame;
  };
  app::BackEnd never_stopped(config), resumed(config);
  add_chain(never_stopped, poses);
  std::vector<std::size_t> mapped;
  for (std::size_t k = 0; k < loop_keyframe; ++k) {
    const std::vector<Eigen::Isometry3d> earlier(poses.begin(), poses.begin() + static_cast<long>(k) + 1);
    EXPECT_FALSE(never_stopped.close_loop(mapped_keyframe(k), k, earlier)) << "keyframe " << k;
    mapped.push_back(k);
  }
  resumed.restore(never_stopped.state(), loop_keyframe + 1, mapped,
                  [&](std::size_t k) { return sequence.dataset.load(k); }, mapped_keyframe);
  const std::optional<app::BackEnd::Loop> a = never_stopped.close_loop(mapped_keyframe(0), loop_keyframe, poses);
  const std::optional<app::BackEnd::Loop> b = resumed.close_loop(mapped_keyframe(0), loop_keyframe, poses);
  ASSERT_TRUE(a && b) << "the view of keyframe 0 seen again closes no loop";
  EXPECT_TRUE(a->accepted);
  EXPECT_EQ(a->matched_keyframe, b->matched_keyframe);
  EXPECT_EQ(a->inliers, b->inliers);
  EXPECT_EQ(a->drift_m, b->drift_m);
  ASSERT_EQ(a->solved.size(), b->solved.size());
  expect_same_poses(a->solved, b->solved);
}

}  // namespace
