#include "slam/slam_system.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

#ifdef __linux__
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

#include "slam/elapsed.h"
#include "splat/error.h"
#include "splat/se3.h"

namespace app {

SlamSystem::SlamSystem(splat::Rasterizer& rasterizer, const SlamConfig& config)
    : config_((config.validate(), config)),
      tracking_rasterizer_(rasterizer),
      tracker_(rasterizer, config_),
      mapper_(rasterizer, config_.mapping),
      back_end_(config_),
      threaded_(false),
      overlapped_(config_.overlap_mapping && mapper_.device_resident() && config_.front_end == "odometry" &&
                  config_.keyframe_render_iterations == 0) {}

SlamSystem::SlamSystem(splat::Rasterizer& tracking_rasterizer, splat::Rasterizer& mapping_rasterizer,
                       const SlamConfig& config)
    : config_((config.validate(), config)),
      tracking_rasterizer_(tracking_rasterizer),
      tracker_(tracking_rasterizer, config_),
      mapper_(mapping_rasterizer, config_.mapping),
      back_end_(config_),
      threaded_(true),
      overlapped_(false) {
  if (&tracking_rasterizer == &mapping_rasterizer) {
    throw splat::Error("SlamSystem: threaded mapping needs a rasterizer of its own, got the tracking one");
  }
}

SlamSystem::~SlamSystem() {
  if (in_flight_ && in_flight_->optimized.valid()) in_flight_->optimized.wait();  // its error goes unreported
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
    pending_.reset();
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

std::shared_ptr<const splat::Gaussians> SlamSystem::map() const {
  std::lock_guard lock(mutex_);
  return map_;
}

Eigen::Isometry3d SlamSystem::pose_of(const FramePose& frame) const {
  if (frame.keyframe == kNoKeyframe) return Eigen::Isometry3d::Identity();  // before the first keyframe
  return keyframe_world_[frame.keyframe] * frame.T_keyframe_cam;
}

std::vector<Eigen::Isometry3d> SlamSystem::trajectory() const {
  std::lock_guard lock(mutex_);
  std::vector<Eigen::Isometry3d> poses;
  poses.reserve(frames_.size());
  for (const FramePose& f : frames_) poses.push_back(pose_of(f));
  return poses;
}

std::size_t SlamSystem::keyframes() const {
  std::lock_guard lock(mutex_);
  return keyframe_world_.size();
}

MappingTotals SlamSystem::mapping_totals() const {
  std::lock_guard lock(mutex_);
  return totals_;
}

std::vector<LoopEvent> SlamSystem::loop_events() const {
  std::lock_guard lock(mutex_);
  return loop_events_;
}

std::size_t SlamSystem::frame_of_keyframe(std::size_t keyframe) const {
  std::size_t seen = 0;
  for (std::size_t i = 0; i < frames_.size(); ++i) {
    if (frames_[i].is_keyframe && seen++ == keyframe) return i;
  }
  return frames_.size();  // the keyframe being processed: its frame is the next one
}

void SlamSystem::apply_tracker_correction(bool frame_begins) {
  Eigen::Isometry3d correction;
  {
    std::lock_guard lock(mutex_);
    correction = tracker_correction_;
    tracker_correction_ = Eigen::Isometry3d::Identity();
    tracking_frame_ = frame_begins;
    keyframes_as_tracked_.reset();
  }
  const double* c = correction.matrix().data();
  bool identity = true;
  for (int k = 0; k < 16; ++k) identity = identity && c[k] == (k % 5 == 0 ? 1.0 : 0.0);
  if (!identity) tracker_.correct(correction);  // no loop closed: the poses stay bit for bit
}

const Eigen::Isometry3d& SlamSystem::keyframe_as_tracked(std::size_t keyframe) const {
  return keyframes_as_tracked_ ? (*keyframes_as_tracked_)[keyframe] : keyframe_world_[keyframe];
}

void SlamSystem::keep_keyframes_as_tracked() {
  if (tracking_frame_ && !keyframes_as_tracked_) keyframes_as_tracked_ = keyframe_world_;
}

namespace {

double frame_mib(const splat::RgbdFrame& frame) {
  return static_cast<double>((frame.rgb.size() + frame.depth.size()) * sizeof(float)) / (1 << 20);
}

}  // namespace

std::vector<Eigen::Isometry3d> SlamSystem::keyframes_up_to(std::size_t keyframe) const {
  // Those tracking added since (threaded, overlapped) follow the last one solved, so a solution
  // does not depend on how far tracking got meanwhile.
  std::lock_guard lock(mutex_);
  return {keyframe_world_.begin(), keyframe_world_.begin() + static_cast<long>(keyframe) + 1};
}

void SlamSystem::close_loops(const KeyframeJob& job) {
  const std::vector<Eigen::Isometry3d> poses = keyframes_up_to(job.keyframe);
  const std::optional<BackEnd::Loop> loop = back_end_.close_loop(job.frame, job.keyframe, poses);
  if (!loop) return;
  std::vector<Eigen::Isometry3d> mapper_corrections;
  {
    std::lock_guard lock(mutex_);
    loop_events_.push_back({frame_of_keyframe(job.keyframe),
                            frame_of_keyframe(loop->matched_keyframe), loop->inliers, loop->drift_m,
                            loop->drift_deg, loop->accepted, std::nullopt});
    if (loop->confirms) loop_events_.back().confirms_frame = frame_of_keyframe(*loop->confirms);
    if (!loop->accepted) return;
    mapper_corrections = move_keyframes(poses, loop->solved);
  }
  mapper_.correct_keyframes(mapper_corrections);
}

std::vector<Eigen::Isometry3d> SlamSystem::move_keyframes(const std::vector<Eigen::Isometry3d>& before,
                                                          const std::vector<Eigen::Isometry3d>& solved) {
  // Keyframes tracking added while the graph was solved (threaded) follow the last solved one.
  keep_keyframes_as_tracked();
  std::vector<Eigen::Isometry3d> correction(keyframe_world_.size());
  for (std::size_t k = 0; k < keyframe_world_.size(); ++k) {
    correction[k] = k < before.size() ? solved[k] * before[k].inverse() : correction[before.size() - 1];
    keyframe_world_[k] = splat::orthonormalized(correction[k] * keyframe_world_[k]);
  }
  tracker_correction_ = correction.back() * tracker_correction_;
  std::vector<Eigen::Isometry3d> mapper_corrections;
  for (std::size_t k : mapper_keyframes_) mapper_corrections.push_back(correction[k]);
  return mapper_corrections;
}

void SlamSystem::link_covisible(const KeyframeJob& job) {
  if (config_.loop_closure.covisible_keyframes <= 0) return;  // with_tracking_reference() gave every job its keyframe
  const std::vector<Eigen::Isometry3d> poses = keyframes_up_to(job.keyframe);
  const BackEnd::Linked linked = back_end_.link_covisible(tracking_reference(job), job.odometry, poses);
  std::vector<Eigen::Isometry3d> mapper_corrections;
  {
    std::lock_guard lock(mutex_);
    totals_.covisible_edges += linked.edges;
    totals_.covisible_rejected += linked.rejected;
    if (linked.solved.empty()) return;
    mapper_corrections = move_keyframes(poses, linked.solved);
  }
  mapper_.correct_keyframes(mapper_corrections);
}

mapping::Vignetting SlamSystem::vignetting() const {
  return mapper_.vignetting();  // mutex_ does not guard the mapper: see the declaration
}

void SlamSystem::rethrow_mapping_error() {
  std::lock_guard lock(mutex_);
  if (error_) std::rethrow_exception(error_);
}

void SlamSystem::with_tracking_reference(KeyframeJob& job) const {
  // Only covisibility reads it: held in mapping's backlog for nothing, the 2.4 MiB of each
  // keyframe's pyramid were fresh memory for tracking's next frames (docs/measurements.md).
  if (config_.front_end != "odometry" || config_.loop_closure.covisible_keyframes <= 0) return;
  job.prepared = tracker_.newest_reference();
  job.pyramid = std::exchange(job.prepared.frame, nullptr);
  job.odometry = tracker_.odometry_config();
}

FrameTracker::PreparedKeyframe SlamSystem::tracking_reference(const KeyframeJob& job) const {
  FrameTracker::PreparedKeyframe prepared = job.prepared;
  prepared.frame = job.pyramid.lock();
  if (!prepared.frame) prepared.frame = prepare_odometry_frame(job.frame, prepared.labels, config_);
  return prepared;
}

double SlamSystem::map_keyframe(const KeyframeJob& job) {
  const auto start = std::chrono::steady_clock::now();
  const mapping::MappingStats stats = optimize_keyframe(job);
  return publish_keyframe(job, stats, ms_since(start));
}

mapping::MappingStats SlamSystem::optimize_keyframe(const KeyframeJob& job) {
  mapper_keyframes_.push_back(job.keyframe);  // the mapper numbers keyframes in the order added
  return mapper_.add_keyframe(job.frame, job.T_world_cam.inverse());
}

double SlamSystem::publish_keyframe(const KeyframeJob& job, const mapping::MappingStats& stats, double optimize_ms) {
  const auto start = std::chrono::steady_clock::now();
  if (config_.loop_closure.enabled && config_.front_end == "odometry") close_loops(job);
  if (config_.front_end == "odometry") link_covisible(job);
  auto snapshot = std::make_shared<const splat::Gaussians>(mapper_.map());
  const auto poses = mapper_.keyframe_poses();
  const double ms = optimize_ms + ms_since(start);
  std::lock_guard lock(mutex_);
  keep_keyframes_as_tracked();
  for (const auto& [number, T_cam_world] : poses) keyframe_world_[mapper_keyframes_[number]] = T_cam_world.inverse();
  map_ = std::move(snapshot);
  ++totals_.keyframes_mapped;
  totals_.gaussians_added += stats.added;
  totals_.gaussians_pruned += stats.pruned;
  totals_.ghosts_pruned += stats.ghosts;
  totals_.iterations += static_cast<std::size_t>(stats.iterations);
  totals_.last_loss = stats.final_loss;
  totals_.mapping_ms += ms;
  return ms;
}

void SlamSystem::start_overlapped(KeyframeJob job) {
  auto flight = std::make_unique<InFlight>(InFlight{std::move(job), {}, {}});
  flight->optimized = std::async(std::launch::async, [this, &job = flight->job] {
    const auto start = std::chrono::steady_clock::now();
    mapping::MappingStats stats = optimize_keyframe(job);
    return std::make_pair(stats, ms_since(start));
  });
  in_flight_ = std::move(flight);  // only once its thread runs
}

void SlamSystem::join_overlapped() {
  if (!in_flight_ || in_flight_->joined) return;
  try {
    in_flight_->joined = in_flight_->optimized.get();
  } catch (...) {
    in_flight_.reset();
    throw;
  }
}

double SlamSystem::finish_overlapped() {
  if (!in_flight_) return 0;
  const auto start = std::chrono::steady_clock::now();
  join_overlapped();
  const std::unique_ptr<InFlight> done = std::move(in_flight_);
  const auto [stats, optimize_ms] = *done->joined;
  publish_keyframe(done->job, stats, optimize_ms);
  apply_tracker_correction();  // a loop it closed moves the motion model now
  return ms_since(start);
}

namespace {
// The first frame seeds the map from its depth: one with less than this fraction of its pixels
// measured (a covered lens, a sensor still starting) is skipped, and the next one tried.
constexpr double kMinSeedDepthFraction = 0.01;

double measured_fraction(const splat::RgbdFrame& frame) {
  std::size_t measured = 0;
  for (float z : frame.depth) measured += z > 0 && std::isfinite(z);
  return frame.depth.empty() ? 0 : static_cast<double>(measured) / static_cast<double>(frame.depth.size());
}

// A keyframe's frame for mapping: the input itself, its depth as tracking moved it to the
// colour's instant. Taken, not copied: mapping keeps keyframes back (threaded, a backlog of
// them), and a copy would be 4.7 MiB (640x480) of fresh memory on tracking's thread each time,
// whose first touches made live's slowest frames (docs/measurements.md).
splat::RgbdFrame for_mapping(splat::RgbdFrame input, const splat::RgbdFrame* synced) {
  if (synced) {
    input.depth.assign(synced->depth.begin(), synced->depth.end());  // into the input's own buffer
    input.depth_time_offset = synced->depth_time_offset;
  }
  return input;
}
}  // namespace

FrameRecord SlamSystem::process(splat::RgbdFrame input, bool held_out) {
  rethrow_mapping_error();
  apply_tracker_correction(true);
  // Depth taken apart from its colour image is moved to the colour's instant where tracking
  // found the camera's velocity (FrameRecord::T_colour_depth): else at a turn of 2 rad/s,
  // 15 ms apart, depth and colour disagree by 2 degrees.
  const splat::RgbdFrame* synced = nullptr;
  auto frame = [&]() -> const splat::RgbdFrame& { return synced ? *synced : input; };
  FrameRecord record;
  const double measured = tracker_.started() ? 1.0 : held_out ? 0.0 : measured_fraction(input);
  if (measured < kMinSeedDepthFraction) {
    record.timestamp = input.timestamp;
    record.tracked = false;
    record.held_out = held_out;
    record.reason = held_out ? "a held-out frame before the first keyframe"
                             : "waiting for a first frame with depth: " + std::to_string(100 * measured) +
                                   "% of its pixels are measured";
    std::lock_guard lock(mutex_);
    frames_.push_back({kNoKeyframe, Eigen::Isometry3d::Identity(), false, false, held_out, {}, {}});
    record.gaussians = 0;
    return record;
  }
  if (!tracker_.started()) {
    record.timestamp = input.timestamp;
    record.keyframe = true;
    tracker_.start(input);
  } else {
    // Threaded, the odometry may track before the first keyframe is mapped, on an empty map.
    const std::shared_ptr<const splat::Gaussians> snapshot = this->map();
    const splat::Gaussians& map = *snapshot;
    record = tracker_.track(map, input, [this](std::size_t k) {
      std::lock_guard lock(mutex_);
      return keyframe_as_tracked(k);
    });
    synced = tracker_.depth_moved_frame();
    if (!record.tracked && !held_out && config_.loop_closure.enabled && config_.front_end == "odometry") {
      // Lost even against the recent keyframes: look for the frame among all of them.
      std::optional<BackEnd::Placement> found =
          back_end_.place(frame(), [](std::size_t) { return true; });
      // A place whose depth does not fit is a view that only looks alike: things that moved as
      // one (a walking person) match as if the camera had moved. The place's spread is measured
      // on the back end's thumbnails (dense_width), the recent spreads at tracking's finest level:
      // a coarse test, which refuses only placements far off.
      if (const double ratio = found ? tracker_.residual_ratio(found->depth_spread) : 0;
          ratio > config_.lost_residual_factor) {
        std::lock_guard lock(mutex_);
        record.reason += "; not relocalized against the keyframe of frame " +
                         std::to_string(frame_of_keyframe(found->keyframe)) + ": " +
                         residual_spread_reason(ratio);
        found.reset();
      }
      if (found) {
        {
          std::lock_guard lock(mutex_);
          record.T_world_cam = splat::orthonormalized(keyframe_as_tracked(found->keyframe) * found->T_keyframe_frame);
          record.reason = "relocalized against the keyframe of frame " + std::to_string(frame_of_keyframe(found->keyframe));
        }
        record.tracked = record.relocalized = true;
        record.reference = found->keyframe;
        record.information = found->information;
        tracker_.relocalized(record);
      }
    }
    // A relocalized frame becomes a keyframe: tracking goes on against it.
    if (!held_out && (record.relocalized || tracker_.wants_keyframe(record))) {
      record.keyframe = true;
      tracker_.refine_keyframe(map, frame(), record);
    }
  }
  // What mapping leaves out of this frame: where moving objects stand.
  const MovingMask moving = record.moving_share > 0 ? MovingMask::arrivals(tracker_.moving_labels(),
                                                                           frame().width() / tracker_.moving_factor(),
                                                                           tracker_.moving_factor())
                                                    : MovingMask{};
  std::optional<KeyframeJob> job;
  // Threaded, mapping may have moved the keyframes while this frame was tracked against them:
  // the frame then moves as a keyframe added before would have (tracking's motion model follows
  // at the next frame).
  Eigen::Isometry3d T_world_cam = record.T_world_cam, T_keyframe_frame = Eigen::Isometry3d::Identity();
  {
    std::lock_guard lock(mutex_);
    if (keyframes_as_tracked_) T_world_cam = splat::orthonormalized(tracker_correction_ * record.T_world_cam);
    if (record.keyframe) {
      job = KeyframeJob{for_mapping(std::move(input), synced), T_world_cam, keyframe_world_.size(), {}, {}, {}};
      moving.apply(job->frame);
      if (record.reference != FrameRecord::kNoReference && record.reference < keyframe_world_.size()) {
        // The odometry edge: this keyframe as measured from its reference.
        back_end_.add_odometry_edge(record.reference, keyframe_world_.size(),
                                    keyframe_as_tracked(record.reference).inverse() * record.T_world_cam,
                                    record.information);
      }
      keyframe_world_.push_back(T_world_cam);
    } else {
      T_keyframe_frame = keyframe_as_tracked(keyframe_world_.size() - 1).inverse() * record.T_world_cam;
    }
    tracking_frame_ = false;
    keyframes_as_tracked_.reset();
  }
  if (job && job->keyframe > 0) tracker_.keyframe_added(record, job->keyframe);
  if (job) with_tracking_reference(*job);
  if (threaded_ && !thread_.joinable()) thread_ = std::thread([this] { mapping_loop(); });
  // The render front end tracks against the map: the first keyframe seeds it before anything
  // is tracked. The odometry needs no map, so threaded it maps even the first in the background.
  const bool map_now = !threaded_ || (job && job->keyframe == 0 && config_.front_end == "render");
  if (job && overlapped_) {
    // The keyframe before is published first (its loops move this one along), then this one
    // is optimized while the next frames are tracked.
    record.mapping_ms = finish_overlapped();
    {
      std::lock_guard lock(mutex_);
      job->T_world_cam = keyframe_world_[job->keyframe];
    }
    start_overlapped(std::move(*job));
  } else if (job && map_now) {
    record.mapping_ms = map_keyframe(*job);
    apply_tracker_correction();  // a loop it closed moves the motion model now
  } else if (job) {
    {
      std::lock_guard lock(mutex_);
      if (pending_) {  // mapping fell behind: the newer one replaces it, the older waits for the end
        ++totals_.keyframes_skipped;
        backlog_mib_ += frame_mib(pending_->frame);
        backlog_.push_back(std::move(*pending_));
        while (!backlog_.empty() && backlog_mib_ > config_.mapping_backlog_mib) {
          backlog_mib_ -= frame_mib(backlog_.front().frame);
          backlog_.pop_front();
        }
      }
      pending_ = std::move(job);
    }
    wake_.notify_one();
  }
  std::lock_guard lock(mutex_);
  const std::size_t keyframe = keyframe_world_.size() - 1;  // this frame, or the last keyframe before it
  frames_.push_back({keyframe, T_keyframe_frame, record.tracked, record.keyframe, held_out, moving, record.T_colour_depth});
  record.T_world_cam = T_world_cam;  // tracking's own poses follow at the next frame
  record.held_out = held_out;
  record.gaussians = map_->size();
  return record;
}

SlamSystem::State SlamSystem::state() {
  // Overlapped, the keyframe in flight is only joined: publishing it here would make a run that
  // saves its state differ from one that does not.
  if (overlapped_) {
    join_overlapped();
  } else {
    wait_for_mapping();
  }
  std::lock_guard lock(mutex_);
  State s{tracker_.state(), mapper_.state(), mapper_keyframes_, keyframe_world_, frames_, totals_,
          back_end_.state(), loop_events_,     tracker_correction_, {}};
  if (in_flight_) {
    s.unpublished = State::Unpublished{in_flight_->job.keyframe, in_flight_->joined->first, in_flight_->joined->second};
  }
  return s;
}

void SlamSystem::restore(State s, const std::function<splat::RgbdFrame(std::size_t)>& load) {
  auto inconsistent = [](const std::string& what) { throw splat::Error("SlamSystem::restore: " + what); };
  if (!frames_.empty() || tracker_.started()) inconsistent("the system has already processed frames");
  // Keyframe number -> frame index, from the frames' own record of which were keyframes.
  std::vector<std::size_t> keyframe_frame;
  for (std::size_t i = 0; i < s.frames.size(); ++i) {
    const FramePose& f = s.frames[i];
    if (f.is_keyframe) keyframe_frame.push_back(i);
    if (f.keyframe != kNoKeyframe && f.keyframe >= keyframe_frame.size()) {
      inconsistent("frame " + std::to_string(i) + " follows keyframe " + std::to_string(f.keyframe) + " of " +
                   std::to_string(keyframe_frame.size()));
    }
  }
  if (keyframe_frame.size() != s.keyframe_world.size() || s.mapper_keyframes.size() != s.mapper.added) {
    inconsistent(std::to_string(keyframe_frame.size()) + " keyframes among the frames, " +
                 std::to_string(s.keyframe_world.size()) + " keyframe poses, " +
                 std::to_string(s.mapper_keyframes.size()) + " mapped of " + std::to_string(s.mapper.added));
  }
  for (std::size_t k : s.mapper_keyframes) {
    if (k >= keyframe_frame.size()) inconsistent("mapped keyframe " + std::to_string(k) + " does not exist");
  }
  if (s.tracker.last_poses.empty() != keyframe_frame.empty()) inconsistent("tracking and keyframes disagree");
  auto keyframe = [&](std::size_t number) {
    if (number >= keyframe_frame.size()) inconsistent("keyframe " + std::to_string(number) + " does not exist");
    const std::size_t i = keyframe_frame[number];
    splat::RgbdFrame frame = load(i);  // its depth moved as process() moved it
    const Eigen::Isometry3d& T = s.frames[i].T_colour_depth;
    if (!T.isApprox(Eigen::Isometry3d::Identity())) splat::move_depth_to_colour_time(frame, T);
    return frame;
  };
  // As mapping was given them: without the moving objects tracking found in them.
  auto mapped_keyframe = [&](std::size_t number) {
    splat::RgbdFrame frame = keyframe(number);
    s.frames[keyframe_frame[number]].moving.apply(frame);
    return frame;
  };
  tracker_.restore(s.tracker, keyframe);
  back_end_.restore(std::move(s.back_end), keyframe_frame.size(), s.mapper_keyframes, keyframe, mapped_keyframe);
  std::unique_ptr<InFlight> unpublished;
  if (s.unpublished) {  // the newest keyframe, as process() handed it to mapping
    const State::Unpublished& u = *s.unpublished;
    if (u.keyframe + 1 != keyframe_frame.size() || s.mapper_keyframes.empty() || s.mapper_keyframes.back() != u.keyframe) {
      inconsistent("the unpublished keyframe " + std::to_string(u.keyframe) + " is not the newest one mapped");
    }
    KeyframeJob job{mapped_keyframe(u.keyframe), s.keyframe_world[u.keyframe], u.keyframe, {}, {}, {}};
    with_tracking_reference(job);
    unpublished = std::make_unique<InFlight>(InFlight{std::move(job), {}, std::make_pair(u.stats, u.optimize_ms)});
  }
  mapper_.restore(std::move(s.mapper), [&](std::size_t number) {
    if (number >= s.mapper_keyframes.size()) inconsistent("mapper keyframe " + std::to_string(number) + " does not exist");
    return mapped_keyframe(s.mapper_keyframes[number]);
  });
  {
    std::lock_guard lock(mutex_);
    mapper_keyframes_ = std::move(s.mapper_keyframes);
    keyframe_world_ = std::move(s.keyframe_world);
    frames_ = std::move(s.frames);
    totals_ = s.totals;
    loop_events_ = std::move(s.loop_events);
    tracker_correction_ = s.tracker_correction;
    map_ = std::make_shared<const splat::Gaussians>(mapper_.map());
  }
  in_flight_ = std::move(unpublished);
  if (!overlapped_) finish_overlapped();  // continued in turn: published now
}

void SlamSystem::mapping_loop() {
#ifdef __linux__
  // Mapping yields the processor to tracking, which must keep up with the camera (Linux sets
  // niceness per thread).
  setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 10);
#endif
  for (;;) {
    KeyframeJob job;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return stop_ || pending_.has_value(); });
      if (stop_ && !pending_) return;
      job = std::move(*pending_);
      pending_.reset();
      job.T_world_cam = keyframe_world_[job.keyframe];  // as loops have moved it while it waited
      busy_ = true;
    }
    try {
      map_keyframe(job);
    } catch (...) {
      std::lock_guard lock(mutex_);
      error_ = std::current_exception();
    }
    {
      std::lock_guard lock(mutex_);
      busy_ = false;
    }
    idle_.notify_all();
  }
}

void SlamSystem::wait_for_mapping() {
  finish_overlapped();
  {
    std::unique_lock lock(mutex_);
    idle_.wait(lock, [&] { return (!pending_ && !busy_) || !thread_.joinable(); });
  }
  rethrow_mapping_error();
}

std::size_t SlamSystem::mapping_backlog() const {
  std::lock_guard lock(mutex_);
  return backlog_.size();
}

std::size_t SlamSystem::catch_up_mapping(const std::function<void(std::size_t, std::size_t)>& mapped,
                                         const std::function<bool()>& stop) {
  wait_for_mapping();  // the mapper is then this thread's: tracking has ended, the queue is empty
  std::deque<KeyframeJob> jobs;
  {
    std::lock_guard lock(mutex_);
    jobs = std::exchange(backlog_, {});
    backlog_mib_ = 0;
  }
  std::size_t done = 0;
  for (KeyframeJob& job : jobs) {
    if (stop && stop()) break;
    {
      std::lock_guard lock(mutex_);
      job.T_world_cam = keyframe_world_[job.keyframe];  // as loops and mapping have moved it since
    }
    map_keyframe(job);
    {
      std::lock_guard lock(mutex_);
      --totals_.keyframes_skipped;
      ++totals_.keyframes_caught_up;
    }
    if (mapped) mapped(++done, jobs.size());
  }
  apply_tracker_correction();
  return done;
}

void SlamSystem::finish() {
  wait_for_mapping();
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  rethrow_mapping_error();
}

}  // namespace app
