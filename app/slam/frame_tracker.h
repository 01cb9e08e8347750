// The tracking half of SLAM: each new frame's pose, from a constant-velocity guess, by one of two
// front ends, retried and recovered on failure; and the keyframe policy.
// - odometry (default): dense RGB-D alignment against the reference keyframe's own colour and
//   depth (tracking/rgbd_odometry.h); its cost does not depend on the map.
// - render: Levenberg-Marquardt through the rasterizer against the map (tracking/tracker.h).
#pragma once
#include <array>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "slam/slam_config.h"
#include "splat/gaussians.h"
#include "splat/rasterizer.h"
#include "splat/rgbd_frame.h"
#include "tracking/exposure_estimate.h"
#include "tracking/moving_regions.h"
#include "tracking/rgbd_odometry.h"

namespace app {

// What the system did with one frame.
struct FrameRecord {
  double timestamp = 0;
  Eigen::Isometry3d T_world_cam =
      Eigen::Isometry3d::Identity();  // as tracked; lost (odometry): as predicted
  bool tracked = true;  // false: tracking failed even after the retries
  bool retried = false;
  bool relocalized = false;  // lost, then placed by matching it against every keyframe
  // Odometry: the depth residuals' spread at the end (tracking::OdometryResult::depth_spread).
  double residual_spread = 0;
  std::string reason;   // why tracking failed
  bool keyframe = false;
  bool held_out = false;  // a test view: tracked, never mapped
  int renders = 0;      // rasterizer forward passes spent on tracking
  double overlap = 1;   // odometry: fraction of the reference's points this frame sees
  double moving_share = 0;  // odometry: share of the frame's pixels found moving (left out)
  // Odometry: how the frame's depth was moved to its colour's instant (the depth camera's pose
  // in the colour camera's, at the velocity tracking found); the identity for synchronized depth.
  Eigen::Isometry3d T_colour_depth = Eigen::Isometry3d::Identity();
  // Odometry: the reference keyframe the pose was measured against, and the information of that
  // measurement (tracking::OdometryResult::information), for the pose graph.
  static constexpr std::size_t kNoReference = static_cast<std::size_t>(-1);
  std::size_t reference = kNoReference;
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  double tracking_ms = 0, mapping_ms = 0;
  std::size_t gaussians = 0;  // in the map after this frame
};

// An odometry alignment's depth residual spread (tracking::OdometryResult::depth_spread, units of
// the modelled sensor noise, depth_noise z^2) over the median of the `recent` tracked frames'
// spreads, that median taken as at least the sensor noise (1): a frame is lost above
// SlamConfig::lost_residual_factor. 0 while fewer than five frames are recent.
double residual_ratio(double spread, std::vector<double> recent);
// Why a frame with residual_ratio() `ratio` counts as lost, for FrameRecord::reason.
std::string residual_spread_reason(double ratio);

// Labels at 1/factor resolution (labels_width wide) spread over a width x height frame, each
// pixel taking its block's (edge blocks extend over the remainder).
std::vector<uint8_t> upsample_labels(const std::vector<uint8_t>& labels, int labels_width, int factor, int width,
                                     int height);

// The scale of tracking::moving_level() for frames `width` wide: the finest odometry level at
// most SlamConfig::moving.max_width wide.
int moving_factor(int width, const SlamConfig& config);
// The frame prepared for odometry with moving regions `labels` (tracking::MovingLabel at
// moving_factor(), or empty: none) ignored. Throws splat::Error if the labels do not fit the frame.
std::shared_ptr<const tracking::OdometryFrame> prepare_odometry_frame(
    const splat::RgbdFrame& frame, const std::vector<uint8_t>& labels, const SlamConfig& config);

class FrameTracker {
 public:
  FrameTracker(splat::Rasterizer& rasterizer, const SlamConfig& config);
  // The first frame defines the world frame and is the first reference keyframe (number 0).
  void start(const splat::RgbdFrame& frame);
  bool started() const { return !last_poses_.empty(); }
  // Tracks a frame. `keyframe_pose(k)` gives keyframe k's camera-to-world pose as the system
  // holds it now (mapping may have moved it). Fills timestamp, pose, tracked, retried, reason,
  // renders, overlap and tracking_ms.
  FrameRecord track(const splat::GaussiansView& map, const splat::RgbdFrame& frame,
                    const std::function<Eigen::Isometry3d(std::size_t)>& keyframe_pose);
  // Whether a tracked frame should become a keyframe; keyframe_added() makes the frame last
  // tracked the new reference, as keyframe `number`.
  bool wants_keyframe(const FrameRecord& record) const;
  // Odometry front end with keyframe_render_iterations > 0: refines a new keyframe's pose
  // through the rasterizer against the map, from the odometry's estimate.
  void refine_keyframe(const splat::GaussiansView& map, const splat::RgbdFrame& frame, FrameRecord& record);
  void keyframe_added(const FrameRecord& record, std::size_t number);
  // The newest reference keyframe as tracking prepared it (moving regions left out), with its
  // angular rate, and the odometry settings tracking aligns with now (its exposure estimate):
  // what the back end needs to align keyframes with each other. Odometry front end only.
  struct PreparedKeyframe {
    std::shared_ptr<const tracking::OdometryFrame> frame;
    std::size_t keyframe = 0;
    double angular_rate = 0;      // rad/s when it was taken: its own motion blur
    std::vector<uint8_t> labels;  // the moving regions left out of it (prepare_odometry_frame())
    Eigen::Matrix<double, 6, 1> twist = Eigen::Matrix<double, 6, 1>::Zero();  // its velocity then (twist())
  };
  PreparedKeyframe newest_reference() const;
  tracking::OdometryConfig odometry_config() const;
  // The last tracked frame's moving regions (tracking::MovingLabel per pixel of
  // tracking::moving_level(), moving_factor() times smaller than the frame), or empty: none found.
  const std::vector<uint8_t>& moving_labels() const { return moving_; }
  // The last tracked frame with its depth moved to its colour's instant (odometry), or null
  // where its depth was taken as it is (FrameRecord::T_colour_depth the identity).
  const splat::RgbdFrame* depth_moved_frame() const { return depth_moved_ ? &moved_ : nullptr; }
  int moving_factor() const { return moving_factor_; }
  // An alignment's depth residual spread against the recently tracked frames' (residual_ratio()).
  double residual_ratio(double spread) const {
    return app::residual_ratio(spread, {residual_spreads_.begin(), residual_spreads_.end()});
  }
  // A lost frame placed by relocalization (record.T_world_cam): the motion model restarts there.
  void relocalized(const FrameRecord& record);
  // The world moved under tracking (a loop closed): the motion model's poses move with it.
  void correct(const Eigen::Isometry3d& world_correction);

  // What tracking carries from one frame to the next, for checkpoints (between frames).
  struct State {
    std::vector<Eigen::Isometry3d> last_poses;  // empty: not started
    std::vector<double> last_times;
    Eigen::Isometry3d last_keyframe = Eigen::Isometry3d::Identity();
    int since_keyframe = 0;
    std::vector<std::size_t> references;  // odometry: reference keyframe numbers, newest first
    std::vector<double> reference_rates;  // and their angular rates
    std::vector<double> residual_spreads;  // the last tracked frames' depth residual spreads
    std::vector<std::array<double, 2>> exposure_samples;  // tracking::ExposureEstimate::samples()
    // Odometry with moving regions: the labels each reference was prepared with (its own
    // moving_labels(), or the prior of a frame tracking lost and relocalized), in the order of
    // `references` (an empty set: none left out), and the last tracked frame's moving_labels().
    std::vector<std::vector<uint8_t>> reference_labels;
    std::vector<uint8_t> moving;
    std::vector<std::array<double, 6>> reference_twists;  // their velocities (PreparedKeyframe::twist); empty: zero
  };
  State state() const;
  // Continues from `state`: `keyframe(number)` gives that keyframe's frame. Throws splat::Error
  // on an inconsistent state.
  void restore(const State& state, const std::function<splat::RgbdFrame(std::size_t number)>& keyframe);

 private:
  using Reference = PreparedKeyframe;
  // The constant-velocity guess for a frame at `timestamp`.
  Eigen::Isometry3d predict(double timestamp) const;
  // The camera's motion over `seconds` at the velocity of the last two tracked poses,
  // T_cam(t)^-1 T_cam(t + seconds); the identity before there are two.
  Eigen::Isometry3d motion_over(double seconds) const;
  // The relative pose between the last two tracked poses and the seconds between them; none
  // before there are two, or when they share a time.
  struct LastMotion {
    Eigen::Isometry3d motion;
    double step;
  };
  std::optional<LastMotion> last_motion() const;
  // The camera's angular velocity (rad/s, camera axes) over the last two tracked poses; zero
  // before there are two.
  Eigen::Vector3d angular_velocity() const;
  // The camera's velocity [v, omega] (camera axes, per second) over the last two tracked poses;
  // zero before there are two.
  Eigen::Matrix<double, 6, 1> twist() const;
  // Odometry against `reference` from `guess` (world poses); fills the record's pose and result.
  bool align(const Reference& reference, const Eigen::Isometry3d& T_world_reference, const Eigen::Isometry3d& guess,
             FrameRecord& record) const;
  void track_odometry(const splat::RgbdFrame& frame, const std::function<Eigen::Isometry3d(std::size_t)>& keyframe_pose,
                      FrameRecord& record);
  // Aligns last_prepared_ against the newest reference from `guess`, then from the last pose and
  // against the older references; false if none converged (record: the first attempt).
  bool align_with_recovery(const Eigen::Isometry3d& guess,
                           const std::function<Eigen::Isometry3d(std::size_t)>& keyframe_pose, FrameRecord& record);
  // Finds the moving regions of a tracked frame and aligns it again without them; `prior_used`:
  // last_prepared_ left out the previous frame's regions.
  void leave_out_moving(const splat::RgbdFrame& frame, const std::function<Eigen::Isometry3d(std::size_t)>& keyframe_pose,
                        bool prior_used, FrameRecord& record);
  // last_prepared_ becomes `frame` prepared with `labels`, which it remembers.
  void prepare_last(const splat::RgbdFrame& frame, std::vector<uint8_t> labels);
  void track_render(const splat::GaussiansView& map, const splat::RgbdFrame& frame, FrameRecord& record);

  splat::Rasterizer& rasterizer_;
  const SlamConfig& config_;
  std::vector<Eigen::Isometry3d> last_poses_;  // the last two tracked camera-to-world poses
  std::vector<double> last_times_;             // and their timestamps
  Eigen::Isometry3d last_keyframe_ = Eigen::Isometry3d::Identity();
  int since_keyframe_ = 0;
  // Odometry: the frame last tracked, prepared (it becomes the reference if it is a keyframe),
  // and the recent references, newest first: a frame lost against the newest is retried against
  // the others.
  std::shared_ptr<const tracking::OdometryFrame> last_prepared_;
  std::vector<uint8_t> last_prepared_labels_;  // the labels last_prepared_ left out
  std::deque<Reference> references_;
  std::deque<double> residual_spreads_;  // depth residual spreads of the last tracked frames
  tracking::ExposureEstimate exposure_;  // odometry: the colour camera's exposure, for the depth weight
  std::vector<uint8_t> moving_;  // the last tracked frame's moving regions (moving_labels())
  splat::RgbdFrame moved_;       // depth_moved_frame(), where depth_moved_
  bool depth_moved_ = false;
  int moving_factor_ = 1;
  // The last aligned frame's velocity, as its rows' instants were corrected with (twist() without
  // a rolling shutter): a new keyframe keeps it.
  mutable Eigen::Matrix<double, 6, 1> frame_twist_ = Eigen::Matrix<double, 6, 1>::Zero();
};

// A keyframe's velocity (PreparedKeyframe::twist) as checkpoints keep it.
std::array<double, 6> twist_array(const Eigen::Matrix<double, 6, 1>& twist);

// Keyframes as tracking prepared them, restored from a checkpoint: keyframe numbers[k], taken at
// angular rate rates[k] and velocity twists[k], with labels[k] left out (`labels` or `twists`
// empty: a checkpoint from before they were kept, none left out, zero). Throws splat::Error naming
// `what` on lists of different lengths, a velocity that is not finite or labels that do not fit
// their keyframe.
std::deque<FrameTracker::PreparedKeyframe> restore_prepared_keyframes(
    const std::vector<std::size_t>& numbers, const std::vector<double>& rates,
    const std::vector<std::vector<uint8_t>>& labels, const std::vector<std::array<double, 6>>& twists,
    const std::function<splat::RgbdFrame(std::size_t)>& keyframe, const SlamConfig& config,
    const std::string& what);

}  // namespace app
