// The SLAM back end: the keyframe pose graph (odometry, covisibility and loop edges), place
// recognition over the mapped keyframes, loop closure and covisibility. It decides where the
// keyframes should be; SlamSystem moves them there, with the map and tracking.
// Threads: tracking adds odometry edges and places lost frames; mapping closes loops and links
// covisible keyframes. Its own locks guard the graph and the places.
#pragma once
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <vector>

#include <Eigen/Geometry>

#include "slam/frame_tracker.h"
#include "slam/slam_config.h"
#include "splat/rgbd_frame.h"
#include "tracking/place_recognition.h"
#include "tracking/pose_graph.h"

namespace app {

class BackEnd {
 public:
  explicit BackEnd(const SlamConfig& config);

  // Tracking's measurement of a new keyframe from its reference (keyframe numbers), with the
  // alignment's information.
  void add_odometry_edge(std::size_t reference, std::size_t keyframe, const Eigen::Isometry3d& T_reference_keyframe,
                         const Eigen::Matrix<double, 6, 6>& information);

  // A frame's place among the mapped keyframes `eligible` admits: the best verified match,
  // densely aligned (relocalization).
  struct Placement {
    std::size_t keyframe;
    Eigen::Isometry3d T_keyframe_frame;
    Eigen::Matrix<double, 6, 6> information;
    int inliers;
    double depth_spread;  // the dense alignment's (tracking::OdometryResult::depth_spread)
  };
  std::optional<Placement> place(const splat::RgbdFrame& frame, const std::function<bool(std::size_t)>& eligible);

  // For a keyframe just mapped (the mapping thread's), given the poses of the keyframes up to it
  // (edges to later ones are left out of the solve). Loop closure: place recognition against the
  // keyframes at least min_separation older, and that graph solved with the loop; the keyframe
  // then joins the places.
  struct Loop {
    std::size_t matched_keyframe = 0;
    int inliers = 0;
    double drift_m = 0, drift_deg = 0;  // the error it revealed in the poses before solving
    bool accepted = false;
    // Accepted together with an earlier detection it agrees with, outside the drift budget
    // (LoopClosureConfig::confirm_within): that detection's keyframe, which is now linked too.
    std::optional<std::size_t> confirms;
    std::vector<Eigen::Isometry3d> solved;  // accepted: every keyframe's pose
  };
  std::optional<Loop> close_loop(const splat::RgbdFrame& frame, std::size_t keyframe,
                                 const std::vector<Eigen::Isometry3d>& poses);
  // Covisibility (LoopClosureConfig::covisible_keyframes): the keyframe as tracking prepared it,
  // aligned against the recent ones, and the graph over them solved with those edges. `poses`:
  // the keyframes up to this one (edges to later ones are left out of the solve).
  struct Linked {
    std::size_t edges = 0, rejected = 0;
    std::vector<Eigen::Isometry3d> solved;  // the poses given, solved; empty: no edge added
  };
  Linked link_covisible(const FrameTracker::PreparedKeyframe& keyframe, const tracking::OdometryConfig& odometry,
                        const std::vector<Eigen::Isometry3d>& poses);

  // For checkpoints: the graph's edges, the rejected loops waiting for confirmation, and
  // covisibility's recent keyframes (numbers, rates).
  struct State {
    std::vector<tracking::PoseGraphEdge> edges;
    std::vector<tracking::PoseGraphEdge> rejected_loops;
    std::vector<std::size_t> covisible;
    std::vector<double> covisible_rates;
    std::vector<std::vector<uint8_t>>
        covisible_labels;  // their moving regions (FrameTracker::PreparedKeyframe)
    std::vector<std::array<double, 6>> covisible_twists;  // their velocities; empty: zero
  };
  State state() const;
  // Continues from `state` on a back end that has seen nothing: `keyframe(number)` gives a
  // keyframe's frame, `mapped_keyframe(number)` the same as mapping had it (its moving regions
  // ignored, as close_loop() saw it), and `mapped` lists the keyframes mapping has (they rejoin
  // the places). Throws splat::Error on a state that does not hold together with `keyframes`
  // keyframes.
  void restore(State state, std::size_t keyframes, const std::vector<std::size_t>& mapped,
               const std::function<splat::RgbdFrame(std::size_t)>& keyframe,
               const std::function<splat::RgbdFrame(std::size_t)>& mapped_keyframe);

 private:
  splat::RgbdFrame thumbnail(const splat::RgbdFrame& frame) const;  // at dense_width
  // The graph's edges between keyframes 0 .. keyframes - 1.
  std::vector<tracking::PoseGraphEdge> edges_among(std::size_t keyframes) const;
  std::optional<Placement> place(const splat::RgbdFrame& thumb, const tracking::PlaceFeatures& features,
                                 const std::function<bool(std::size_t)>& eligible);

  const SlamConfig& config_;
  mutable std::mutex graph_mutex_;  // guards edges_
  std::vector<tracking::PoseGraphEdge> edges_;  // keyframe numbers; odometry, covisibility and accepted loops
  std::mutex places_mutex_;  // guards places_ and thumbnails_
  tracking::PlaceDatabase places_;
  std::vector<std::pair<std::size_t, splat::RgbdFrame>> thumbnails_;  // keyframe, at dense_width
  std::deque<FrameTracker::PreparedKeyframe> covisible_;  // the mapping thread's: recent keyframes
  // The mapping thread's: loops the drift budget rejected, waiting for a detection to confirm them.
  std::deque<tracking::PoseGraphEdge> rejected_loops_;
};

}  // namespace app
