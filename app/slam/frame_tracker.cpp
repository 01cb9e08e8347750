#include "slam/frame_tracker.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

#include "slam/elapsed.h"
#include "splat/error.h"
#include "splat/se3.h"
#include "tracking/tracker.h"

namespace app {

std::vector<uint8_t> upsample_labels(const std::vector<uint8_t>& labels, int labels_width, int factor, int width,
                                     int height) {
  std::vector<uint8_t> out(static_cast<std::size_t>(width) * height, 0);
  if (labels.empty() || labels_width <= 0) return out;
  const int labels_height = static_cast<int>(labels.size()) / labels_width;
  for (int y = 0; y < height; ++y) {
    const int ly = std::min(y / factor, labels_height - 1);
    for (int x = 0; x < width; ++x) {
      out[static_cast<std::size_t>(y) * width + x] =
          labels[static_cast<std::size_t>(ly) * labels_width + std::min(x / factor, labels_width - 1)];
    }
  }
  return out;
}

int moving_factor(int width, const SlamConfig& config) {
  const std::vector<int> factors = tracking::OdometryFrame::factors(width, config.odometry);
  std::size_t level = 0;
  while (level + 1 < factors.size() && width / factors[level + 1] <= config.moving.max_width)
    ++level;
  return factors[level];
}

namespace {

// Throws splat::Error, naming `what`, unless `labels` are empty or of the moving regions' size
// (scale `factor`) for `frame`.
void check_labels_fit(const splat::RgbdFrame& frame, const std::vector<uint8_t>& labels, int factor,
                      const std::string& what) {
  const int labels_width = frame.width() / factor, labels_height = frame.height() / factor;
  if (!labels.empty() && labels.size() != static_cast<std::size_t>(labels_width) *
                                              static_cast<std::size_t>(labels_height)) {
    throw splat::Error(what + ": " + std::to_string(labels.size()) +
                       " moving labels do not fit a frame of " + std::to_string(frame.width()) +
                       "x" + std::to_string(frame.height()) + " (" + std::to_string(labels_width) +
                       "x" + std::to_string(labels_height) + " labels)");
  }
}

}  // namespace

std::shared_ptr<const tracking::OdometryFrame> prepare_odometry_frame(
    const splat::RgbdFrame& frame, const std::vector<uint8_t>& labels, const SlamConfig& config) {
  if (labels.empty())
    return std::make_shared<const tracking::OdometryFrame>(frame, config.odometry);
  const int factor = moving_factor(frame.width(), config);
  check_labels_fit(frame, labels, factor, "prepare_odometry_frame");
  // Where an object left, the frame shows the static scene: only where one stands (and around
  // it) is ignored, besides what the frame ignores itself (classes its labels call dynamic).
  tracking::OdometryFrame::LeftOut left_out{std::vector<uint8_t>(labels.size()), factor};
  for (std::size_t i = 0; i < labels.size(); ++i) {
    left_out.reasons[i] = labels[i] == tracking::kArrived   ? tracking::kMovingSurface
                          : labels[i] == tracking::kOutline ? tracking::kOutlineIgnored
                                                            : 0;
  }
  return std::make_shared<const tracking::OdometryFrame>(frame, config.odometry, left_out);
}

std::array<double, 6> twist_array(const Eigen::Matrix<double, 6, 1>& twist) {
  std::array<double, 6> out;
  Eigen::Map<Eigen::Matrix<double, 6, 1>>(out.data()) = twist;
  return out;
}

namespace {

Eigen::Matrix<double, 6, 1> twist_from_array(const std::array<double, 6>& twist) {
  return Eigen::Map<const Eigen::Matrix<double, 6, 1>>(twist.data());
}

}  // namespace

std::deque<FrameTracker::PreparedKeyframe> restore_prepared_keyframes(
    const std::vector<std::size_t>& numbers, const std::vector<double>& rates,
    const std::vector<std::vector<uint8_t>>& labels, const std::vector<std::array<double, 6>>& twists,
    const std::function<splat::RgbdFrame(std::size_t)>& keyframe, const SlamConfig& config,
    const std::string& what) {
  if (rates.size() != numbers.size() || (!labels.empty() && labels.size() != numbers.size()) ||
      (!twists.empty() && twists.size() != numbers.size())) {
    throw splat::Error(what + ": " + std::to_string(numbers.size()) + " keyframes with " +
                       std::to_string(rates.size()) + " angular rates, " + std::to_string(twists.size()) +
                       " velocities and " + std::to_string(labels.size()) + " label sets");
  }
  for (const std::array<double, 6>& t : twists) {
    if (!std::all_of(t.begin(), t.end(), [](double v) { return std::isfinite(v); }))
      throw splat::Error(what + ": a keyframe's velocity is not finite");
  }
  std::deque<FrameTracker::PreparedKeyframe> prepared;
  for (std::size_t k = 0; k < numbers.size(); ++k) {
    const splat::RgbdFrame frame = keyframe(numbers[k]);
    std::vector<uint8_t> left_out = labels.empty() ? std::vector<uint8_t>{} : labels[k];
    check_labels_fit(frame, left_out, moving_factor(frame.width(), config),
                     what + ", keyframe " + std::to_string(numbers[k]));
    prepared.push_back({prepare_odometry_frame(frame, left_out, config), numbers[k], rates[k],
                        std::move(left_out),
                        twists.empty() ? Eigen::Matrix<double, 6, 1>::Zero() : twist_from_array(twists[k])});
  }
  return prepared;
}

double residual_ratio(double spread, std::vector<double> recent) {
  if (recent.size() < 5) return 0;
  std::nth_element(recent.begin(), recent.begin() + static_cast<long>(recent.size() / 2), recent.end());
  // Never below the sensor noise: on noise-free depth the median is far under it, and a surface
  // coming into view read as lost at a correct pose (docs/tuning.md).
  return spread / std::max(recent[recent.size() / 2], 1.0);
}

std::string residual_spread_reason(double ratio) {
  return "depth residuals spread " + std::to_string(ratio) +
         " times the recent median (or the sensor noise)";
}

FrameTracker::FrameTracker(splat::Rasterizer& rasterizer, const SlamConfig& config)
    : rasterizer_(rasterizer), config_(config), exposure_(config_.odometry) {}

void FrameTracker::start(const splat::RgbdFrame& frame) {
  last_poses_ = {Eigen::Isometry3d::Identity()};
  last_times_ = {frame.timestamp};
  last_keyframe_ = Eigen::Isometry3d::Identity();
  since_keyframe_ = 0;
  references_.clear();
  if (config_.front_end == "odometry") {
    references_.push_front({prepare_odometry_frame(frame, {}, config_), 0, 0, {}});
  }
}

Eigen::Isometry3d FrameTracker::predict(double timestamp) const {
  // Constant velocity: the last inter-frame motion, scaled to this frame's time step (equal
  // steps when the timestamps do not say otherwise), which bridges dropped frames.
  const Eigen::Isometry3d last = last_poses_.back();
  if (last_poses_.size() < 2) return last;
  const double step = last_times_.back() - last_times_.front(), now = timestamp - last_times_.back();
  const double scale = step > 0 && now > 0 ? std::min(now / step, 10.0) : 1.0;
  const Eigen::Isometry3d motion = last_poses_.front().inverse() * last;
  return splat::orthonormalized(last * (scale == 1.0 ? motion : splat::se3_exp(scale * splat::se3_log(motion))));
}

FrameRecord FrameTracker::track(const splat::GaussiansView& map, const splat::RgbdFrame& frame,
                                const std::function<Eigen::Isometry3d(std::size_t)>& keyframe_pose) {
  FrameRecord record;
  record.timestamp = frame.timestamp;
  depth_moved_ = false;
  const auto start = std::chrono::steady_clock::now();
  if (config_.front_end == "odometry") {
    track_odometry(frame, keyframe_pose, record);
    // A lost frame's alignment is what the tests refused; the camera moved on as it was moving.
    if (!record.tracked) record.T_world_cam = predict(frame.timestamp);
  } else {
    track_render(map, frame, record);
  }
  record.tracking_ms = ms_since(start);
  // A failed frame's pose is a guess: the motion model keeps the last tracked poses.
  if (record.tracked && config_.front_end == "odometry") {
    residual_spreads_.push_back(record.residual_spread);
    if (residual_spreads_.size() > 20) residual_spreads_.pop_front();
  }
  if (record.tracked) {
    const bool first_motion = last_poses_.size() == 1;
    last_poses_ = {last_poses_.back(), record.T_world_cam};
    last_times_ = {last_times_.back(), frame.timestamp};
    // The first keyframe's velocity is known once the next frame is placed.
    if (first_motion && references_.size() == 1 && references_.front().keyframe == 0)
      references_.front().twist = twist();
    if (config_.front_end == "odometry") exposure_.observe(*last_prepared_, angular_velocity());
  }
  ++since_keyframe_;
  return record;
}

std::optional<FrameTracker::LastMotion> FrameTracker::last_motion() const {
  if (last_poses_.size() < 2) return std::nullopt;
  const double step = last_times_.back() - last_times_.front();
  if (!(step > 0)) return std::nullopt;
  return LastMotion{last_poses_.front().inverse() * last_poses_.back(), step};
}

Eigen::Isometry3d FrameTracker::motion_over(double seconds) const {
  const std::optional<LastMotion> m = last_motion();
  if (!m) return Eigen::Isometry3d::Identity();
  return splat::se3_exp(seconds / m->step * splat::se3_log(m->motion));
}

Eigen::Matrix<double, 6, 1> FrameTracker::twist() const {
  const std::optional<LastMotion> m = last_motion();
  if (!m) return Eigen::Matrix<double, 6, 1>::Zero();
  return splat::se3_log(m->motion) / m->step;
}

Eigen::Vector3d FrameTracker::angular_velocity() const {
  const std::optional<LastMotion> m = last_motion();
  if (!m) return Eigen::Vector3d::Zero();
  const Eigen::AngleAxisd turn(m->motion.linear());
  return turn.axis() * (turn.angle() / m->step);
}

bool FrameTracker::align(const Reference& reference, const Eigen::Isometry3d& T_world_reference,
                         const Eigen::Isometry3d& guess, FrameRecord& record) const {
  tracking::OdometryConfig odometry = odometry_config();
  odometry.depth_weight =
      tracking::blur_aware_depth_weight(odometry, *last_prepared_, angular_velocity().norm(), reference.angular_rate);
  const Eigen::Matrix<double, 6, 1> last_twist = twist();
  tracking::OdometryResult r = tracking::align_rgbd(
      *reference.frame, *last_prepared_, guess.inverse() * T_world_reference, odometry, {reference.twist, last_twist});
  frame_twist_ = last_twist;
  const double dt = last_times_.empty() ? 0 : last_prepared_->timestamp() - last_times_.back();
  if (odometry.rolling_shutter > 0 && r.converged && dt > 0 && last_poses_.size() == 2) {
    // The rows' instants need the velocity at this frame: the last two velocities (centred half
    // a frame and a frame and a half back) extrapolated to it, and the frame aligned again.
    const Eigen::Matrix<double, 6, 1> back =
        splat::se3_log(last_poses_.back().inverse() * (T_world_reference * r.T_cur_ref.inverse())) / dt;
    frame_twist_ = back + 0.5 * (back - last_twist);
    r = tracking::align_rgbd(*reference.frame, *last_prepared_, r.T_cur_ref, odometry, {reference.twist, frame_twist_});
  }
  record.T_world_cam = T_world_reference * r.T_cur_ref.inverse();
  record.tracked = r.converged;
  record.reason = r.reason;
  record.residual_spread = r.depth_spread;
  if (r.converged && config_.odometry.depth_weight > 0) {
    const double ratio = residual_ratio(r.depth_spread);
    if (ratio > config_.lost_residual_factor) {
      record.tracked = false;
      record.reason = residual_spread_reason(ratio);
    }
  }
  record.overlap = r.overlap;
  record.reference = reference.keyframe;
  record.information = r.information;
  return r.converged;
}

void FrameTracker::prepare_last(const splat::RgbdFrame& frame, std::vector<uint8_t> labels) {
  last_prepared_ = prepare_odometry_frame(frame, labels, config_);
  last_prepared_labels_ = std::move(labels);
}

void FrameTracker::track_odometry(const splat::RgbdFrame& frame,
                                  const std::function<Eigen::Isometry3d(std::size_t)>& keyframe_pose,
                                  FrameRecord& record) {
  const bool detect = config_.moving.enabled;
  moving_factor_ = app::moving_factor(frame.width(), config_);
  // The previous frame's moving regions, grown to where they may have gone, stay out of the
  // first alignment: a large moving object could pull it off before its regions are found.
  const std::vector<uint8_t> prior =
      detect && !moving_.empty()
          ? tracking::grow_regions(moving_, frame.width() / moving_factor_, frame.height() / moving_factor_,
                                   config_.moving.prior_grow_px)
          : std::vector<uint8_t>{};
  // Depth taken apart from its colour image is moved to the colour's instant: first at the
  // velocity of the last frames, then, the frame placed, at the velocity from the last frame to
  // this one (at a turn the prediction is late), and the frame aligned again.
  // Depth that would move by less than a tenth of a pixel is taken as it is (TUM fr3's offsets
  // of hundredths of a millisecond), and the second alignment is left to depth that moves by
  // half a pixel or more (a fraction of which the prediction can miss); translation counts as
  // seen at 1 m.
  const Eigen::Isometry3d predicted_motion = motion_over(frame.depth_time_offset);
  const double shift_px = frame.camera.fx * (Eigen::AngleAxisd(predicted_motion.linear()).angle() +
                                             predicted_motion.translation().norm() / 1.0);
  const double offset = shift_px > 0.1 ? frame.depth_time_offset : 0.0;
  auto depth_moved_by = [&](const Eigen::Isometry3d& T_colour_depth) -> const splat::RgbdFrame& {
    // Into the buffers of the frames before: fresh memory's first touches made live's slowest
    // frames (docs/measurements.md).
    moved_ = frame;
    splat::move_depth_to_colour_time(moved_, T_colour_depth);
    depth_moved_ = true;
    record.T_colour_depth = T_colour_depth;
    return moved_;
  };
  prepare_last(offset != 0 ? depth_moved_by(predicted_motion) : frame, prior);
  bool tracked = align_with_recovery(predict(frame.timestamp), keyframe_pose, record);
  const double step = last_times_.empty() ? 0 : frame.timestamp - last_times_.back();
  if (tracked && shift_px >= 0.5 && step > 0) {
    const Eigen::Isometry3d motion = last_poses_.back().inverse() * record.T_world_cam;
    prepare_last(depth_moved_by(splat::se3_exp(offset / step * splat::se3_log(motion))), prior);
    const auto reference = std::find_if(references_.begin(), references_.end(),
                                        [&](const Reference& r) { return r.keyframe == record.reference; });
    FrameRecord again = record;
    if (reference != references_.end() && align(*reference, keyframe_pose(reference->keyframe), record.T_world_cam, again)) {
      again.retried = record.retried;
      record = again;
    }
  }
  moving_.clear();
  if (detect && tracked)
    leave_out_moving(depth_moved_ ? moved_ : frame, keyframe_pose, !prior.empty(), record);
}

void FrameTracker::leave_out_moving(const splat::RgbdFrame& frame,
                                    const std::function<Eigen::Isometry3d(std::size_t)>& keyframe_pose,
                                    bool prior_used, FrameRecord& record) {
  const auto reference = std::find_if(references_.begin(), references_.end(),
                                      [&](const Reference& r) { return r.keyframe == record.reference; });
  if (reference == references_.end()) return;
  const Eigen::Isometry3d T_world_reference = keyframe_pose(reference->keyframe);
  const Eigen::Isometry3d T_cur_ref = record.T_world_cam.inverse() * T_world_reference;
  // Found on the frame as prepared without any regions left out: the prior's pixels are judged too.
  const std::shared_ptr<const tracking::OdometryFrame> whole =
      prior_used ? prepare_odometry_frame(frame, {}, config_) : last_prepared_;
  std::vector<uint8_t> labels =
      tracking::moving_regions(*reference->frame, *whole, T_cur_ref, config_.odometry, config_.moving, moving_);
  const auto moving = static_cast<std::size_t>(
      std::count_if(labels.begin(), labels.end(), [](uint8_t l) { return l == tracking::kArrived || l == tracking::kOutline; }));
  if (moving == 0) {
    if (whole != last_prepared_) {  // the prior was left out for nothing: align the whole frame
      last_prepared_ = whole;
      last_prepared_labels_.clear();
      FrameRecord again = record;
      if (align(*reference, T_world_reference, record.T_world_cam, again)) record = again;
    }
    return;
  }
  record.moving_share = static_cast<double>(moving) / static_cast<double>(labels.size());
  moving_ = std::move(labels);
  prepare_last(frame, moving_);
  FrameRecord again = record;
  if (align(*reference, T_world_reference, record.T_world_cam, again)) {
    again.retried = record.retried;
    record = again;
  }
}

bool FrameTracker::align_with_recovery(const Eigen::Isometry3d& guess,
                                       const std::function<Eigen::Isometry3d(std::size_t)>& keyframe_pose,
                                       FrameRecord& record) {
  const Reference& newest = references_.front();
  if (align(newest, keyframe_pose(newest.keyframe), guess, record)) return true;
  // Lost: from the last pose (no motion; unless that was the guess), then against the older
  // references.
  FrameRecord first_try = record;
  record.retried = true;
  const Eigen::Matrix4d& g = guess.matrix();
  const bool guess_was_last = std::equal(g.data(), g.data() + 16, last_poses_.back().matrix().data());
  if (!guess_was_last && align(newest, keyframe_pose(newest.keyframe), last_poses_.back(), record)) return true;
  for (std::size_t k = 1; k < references_.size(); ++k) {
    if (align(references_[k], keyframe_pose(references_[k].keyframe), last_poses_.back(), record)) return true;
  }
  record = first_try;  // nothing converged: report the first attempt
  record.retried = true;
  return false;
}

void FrameTracker::refine_keyframe(const splat::GaussiansView& map, const splat::RgbdFrame& frame, FrameRecord& record) {
  if (config_.front_end != "odometry" || config_.keyframe_render_iterations <= 0 || !record.tracked) return;
  const auto start = std::chrono::steady_clock::now();
  tracking::TrackingConfig t = config_.tracking;
  t.pyramid = {t.pyramid.back()};
  t.iterations = {config_.keyframe_render_iterations};
  const tracking::TrackingResult r = tracking::track_frame(rasterizer_, map, frame, record.T_world_cam.inverse(), t);
  record.renders += r.renders;
  if (r.converged) {
    record.T_world_cam = r.T_cam_world.inverse();
    last_poses_.back() = record.T_world_cam;
  }
  record.tracking_ms += ms_since(start);
}

void FrameTracker::track_render(const splat::GaussiansView& map, const splat::RgbdFrame& frame, FrameRecord& record) {
  const Eigen::Isometry3d guess = predict(frame.timestamp), last = last_poses_.back();
  tracking::TrackingResult result = tracking::track_frame(rasterizer_, map, frame, guess.inverse(), config_.tracking);
  record.renders = result.renders;
  if (!result.converged) {
    // Retry from the last pose with the first-order warm-up, which has a wider basin.
    tracking::TrackingConfig retry = config_.tracking;
    retry.warmup_iterations = config_.retry_warmup_iterations;
    const tracking::TrackingResult second = tracking::track_frame(rasterizer_, map, frame, last.inverse(), retry);
    record.retried = true;
    record.renders += second.renders;
    if (second.converged || second.final_cost < result.final_cost) result = second;
  }
  record.tracked = result.converged;
  record.reason = result.reason;
  record.T_world_cam = result.T_cam_world.inverse();
}

bool FrameTracker::wants_keyframe(const FrameRecord& record) const {
  if (!record.tracked) return false;
  const Eigen::Isometry3d motion = last_keyframe_.inverse() * record.T_world_cam;
  const double degrees = Eigen::AngleAxisd(motion.linear()).angle() * 180 / M_PI;
  return since_keyframe_ >= config_.keyframe_every || motion.translation().norm() > config_.keyframe_translation ||
         degrees > config_.keyframe_rotation_deg || record.overlap < config_.keyframe_overlap;
}

void FrameTracker::keyframe_added(const FrameRecord& record, std::size_t number) {
  last_keyframe_ = record.T_world_cam;
  since_keyframe_ = 0;
  if (config_.front_end != "odometry") return;
  references_.push_front(
      {last_prepared_, number, angular_velocity().norm(), last_prepared_labels_, frame_twist_});
  if (references_.size() > static_cast<std::size_t>(config_.recovery_keyframes) + 1) references_.pop_back();
}

FrameTracker::PreparedKeyframe FrameTracker::newest_reference() const {
  if (references_.empty()) return {};
  return references_.front();
}

tracking::OdometryConfig FrameTracker::odometry_config() const {
  tracking::OdometryConfig odometry = config_.odometry;
  odometry.exposure = exposure_.exposure();
  return odometry;
}

void FrameTracker::relocalized(const FrameRecord& record) {
  last_poses_ = {record.T_world_cam};
  last_times_ = {record.timestamp};
}

void FrameTracker::correct(const Eigen::Isometry3d& world_correction) {
  for (Eigen::Isometry3d& T : last_poses_) T = splat::orthonormalized(world_correction * T);
  last_keyframe_ = splat::orthonormalized(world_correction * last_keyframe_);
}

FrameTracker::State FrameTracker::state() const {
  State s{last_poses_,
          last_times_,
          last_keyframe_,
          since_keyframe_,
          {},
          {},
          {residual_spreads_.begin(), residual_spreads_.end()},
          exposure_.samples(),
          {},
          moving_,
          {}};
  for (const Reference& r : references_) {
    s.references.push_back(r.keyframe);
    s.reference_rates.push_back(r.angular_rate);
    s.reference_labels.push_back(r.labels);
    s.reference_twists.push_back(twist_array(r.twist));
  }
  return s;
}

void FrameTracker::restore(const State& s, const std::function<splat::RgbdFrame(std::size_t number)>& keyframe) {
  const bool odometry = config_.front_end == "odometry";
  if (s.last_poses.size() > 2 || s.last_times.size() != s.last_poses.size() ||
      s.references.size() > static_cast<std::size_t>(config_.recovery_keyframes) + 1 ||
      !std::all_of(s.reference_rates.begin(), s.reference_rates.end(),
                   [](double r) { return r >= 0 && std::isfinite(r); }) ||
      (odometry && s.references.empty() != s.last_poses.empty()) ||
      (!odometry && !s.references.empty())) {
    throw splat::Error("FrameTracker::restore: " + std::to_string(s.last_poses.size()) + " poses, " +
                       std::to_string(s.last_times.size()) + " times and " + std::to_string(s.references.size()) +
                       " references do not fit front end " + config_.front_end);
  }
  std::deque<Reference> references =
      restore_prepared_keyframes(s.references, s.reference_rates, s.reference_labels, s.reference_twists, keyframe,
                                 config_, "tracking's references");
  // The last frame's labels (the next frame's prior) are at the references' scale.
  if (!s.moving.empty()) {
    if (references.empty())
      throw splat::Error("FrameTracker::restore: moving labels without a reference");
    const splat::RgbdFrame frame = keyframe(references.front().keyframe);
    check_labels_fit(frame, s.moving, app::moving_factor(frame.width(), config_),
                     "the last frame's moving labels");
  }
  last_poses_ = s.last_poses;
  last_times_ = s.last_times;
  last_keyframe_ = s.last_keyframe;
  since_keyframe_ = s.since_keyframe;
  references_ = std::move(references);
  residual_spreads_.assign(s.residual_spreads.begin(), s.residual_spreads.end());
  exposure_.restore(s.exposure_samples);
  moving_ = s.moving;
  last_prepared_.reset();  // set by the next track() before anything reads it
  last_prepared_labels_.clear();
}

}  // namespace app
