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
      threaded_(false),
      places_(config_.loop_closure.places) {}

SlamSystem::SlamSystem(splat::Rasterizer& tracking_rasterizer, splat::Rasterizer& mapping_rasterizer,
                       const SlamConfig& config)
    : config_((config.validate(), config)),
      tracking_rasterizer_(tracking_rasterizer),
      tracker_(tracking_rasterizer, config_),
      mapper_(mapping_rasterizer, config_.mapping),
      threaded_(true),
      places_(config_.loop_closure.places) {
  if (&tracking_rasterizer == &mapping_rasterizer) {
    throw splat::Error("SlamSystem: threaded mapping needs a rasterizer of its own, got the tracking one");
  }
}

SlamSystem::~SlamSystem() {
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

void SlamSystem::apply_tracker_correction() {
  Eigen::Isometry3d correction;
  {
    std::lock_guard lock(mutex_);
    correction = tracker_correction_;
    tracker_correction_ = Eigen::Isometry3d::Identity();
  }
  const double* c = correction.matrix().data();
  bool identity = true;
  for (int k = 0; k < 16; ++k) identity = identity && c[k] == (k % 5 == 0 ? 1.0 : 0.0);
  if (!identity) tracker_.correct(correction);  // no loop closed: the poses stay bit for bit
}

namespace {

double frame_mib(const splat::RgbdFrame& frame) {
  return static_cast<double>((frame.rgb.size() + frame.depth.size()) * sizeof(float)) / (1 << 20);
}

// The information of an odometry edge, made positive definite: a direction the alignment could
// not observe (a flat wall's slide) gets a vanishing weight rather than none.
Eigen::Matrix<double, 6, 6> edge_information(const Eigen::Matrix<double, 6, 6>& information) {
  const double scale = std::max(information.trace() / 6, 1.0);
  return 0.5 * (information + information.transpose()) + 1e-9 * scale * Eigen::Matrix<double, 6, 6>::Identity();
}

}  // namespace

splat::RgbdFrame SlamSystem::thumbnail(const splat::RgbdFrame& frame) const {
  const int factor = std::max(1, frame.width() / config_.loop_closure.dense_width);
  return splat::downsample(frame, factor);
}

std::optional<SlamSystem::Placement> SlamSystem::place(const splat::RgbdFrame& thumb, const tracking::PlaceFeatures& features,
                                                      const std::function<bool(std::size_t)>& eligible) {
  std::vector<tracking::PlaceMatch> matches;
  splat::RgbdFrame matched;
  {
    std::lock_guard lock(places_mutex_);
    matches = places_.query(features, eligible);
    if (matches.empty()) return std::nullopt;
    const auto it = std::find_if(thumbnails_.begin(), thumbnails_.end(),
                                 [&](const auto& t) { return t.first == matches.front().keyframe; });
    if (it == thumbnails_.end()) return std::nullopt;
    matched = it->second;
  }
  const tracking::PlaceMatch& m = matches.front();
  // Dense alignment of the two views from the RANSAC estimate.
  tracking::OdometryConfig dense = config_.odometry;
  dense.finest_width = matched.width();
  const tracking::OdometryFrame reference(matched, dense), current(thumb, dense);
  const tracking::OdometryResult aligned = tracking::align_rgbd(reference, current, m.T_keyframe_query.inverse(), dense);
  if (!aligned.converged) return std::nullopt;
  return Placement{m.keyframe, aligned.T_cur_ref.inverse(), edge_information(aligned.information), m.inliers};
}

void SlamSystem::close_loops(const KeyframeJob& job) {
  const LoopClosureConfig& lc = config_.loop_closure;
  tracking::PlaceFeatures features = tracking::extract_place_features(job.frame, lc.places);
  const splat::RgbdFrame thumb = thumbnail(job.frame);
  const std::size_t separation = static_cast<std::size_t>(lc.min_separation);
  const std::optional<Placement> found = place(thumb, features, [&](std::size_t k) { return k + separation <= job.keyframe; });
  {
    std::lock_guard lock(places_mutex_);
    places_.add(job.keyframe, std::move(features));
    thumbnails_.emplace_back(job.keyframe, thumb);
  }
  if (!found) return;
  tracking::PoseGraphEdge loop;
  loop.i = found->keyframe, loop.j = job.keyframe, loop.loop = true;
  loop.T_i_j = found->T_keyframe_frame;
  loop.information = found->information;
  std::vector<Eigen::Isometry3d> poses;
  std::vector<tracking::PoseGraphEdge> edges;
  LoopEvent event;
  {
    std::lock_guard lock(mutex_);
    poses = keyframe_world_;
    edges = edges_;
    event.frame = frame_of_keyframe(job.keyframe);
    event.matched_frame = frame_of_keyframe(found->keyframe);
  }
  edges.push_back(loop);
  const Eigen::Isometry3d revealed = (poses[loop.i].inverse() * poses[loop.j]).inverse() * loop.T_i_j;
  event.inliers = found->inliers;
  event.drift_m = revealed.translation().norm();
  event.drift_deg = Eigen::AngleAxisd(revealed.linear()).angle() * 180 / M_PI;
  const tracking::PoseGraphResult solved = tracking::optimize_pose_graph(poses, edges, {0}, lc.graph);
  event.accepted = solved.accepted.back();
  std::vector<Eigen::Isometry3d> mapper_corrections;
  {
    std::lock_guard lock(mutex_);
    loop_events_.push_back(event);
    if (!event.accepted) return;
    edges_.push_back(loop);
    mapper_corrections = move_keyframes(poses, solved.poses);
  }
  mapper_.correct_keyframes(mapper_corrections);
}

std::vector<Eigen::Isometry3d> SlamSystem::move_keyframes(const std::vector<Eigen::Isometry3d>& before,
                                                          const std::vector<Eigen::Isometry3d>& solved) {
  // Keyframes tracking added while the graph was solved (threaded) follow the last solved one.
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

namespace {

// The pose graph solved for the keyframes from `first` on alone, with every keyframe outside
// them that an edge links them to held where it is: the cost stays that of the window however
// long the run (loops solve the whole graph). The poses of all keyframes, the others unmoved.
std::vector<Eigen::Isometry3d> solve_window(const std::vector<Eigen::Isometry3d>& poses,
                                            const std::vector<tracking::PoseGraphEdge>& edges, std::size_t first,
                                            const tracking::PoseGraphConfig& config) {
  std::vector<std::size_t> node(poses.size(), poses.size());  // keyframe -> window node
  std::vector<std::size_t> keyframe;                          // window node -> keyframe
  std::vector<std::size_t> fixed;
  const auto add = [&](std::size_t k, bool hold) {
    if (node[k] != poses.size()) return;
    node[k] = keyframe.size();
    keyframe.push_back(k);
    if (hold) fixed.push_back(node[k]);
  };
  for (std::size_t k = first; k < poses.size(); ++k) add(k, k == 0);
  std::vector<tracking::PoseGraphEdge> window;
  for (const tracking::PoseGraphEdge& e : edges) {
    if (e.i < first && e.j < first) continue;
    add(e.i, true), add(e.j, true);  // a neighbour outside the window: held
    tracking::PoseGraphEdge w = e;
    w.i = node[e.i], w.j = node[e.j];
    window.push_back(w);
  }
  if (fixed.empty()) fixed.push_back(node[first]);  // nothing links the window to the rest: its first holds it
  std::vector<Eigen::Isometry3d> initial;
  for (std::size_t k : keyframe) initial.push_back(poses[k]);
  const tracking::PoseGraphResult solved = tracking::optimize_pose_graph(initial, window, fixed, config);
  std::vector<Eigen::Isometry3d> out = poses;
  for (std::size_t n = 0; n < keyframe.size(); ++n) out[keyframe[n]] = solved.poses[n];
  return out;
}

}  // namespace

void SlamSystem::link_covisible(const KeyframeJob& job) {
  const int wanted = config_.loop_closure.covisible_keyframes;
  if (wanted <= 0 || !job.prepared.frame) return;
  std::vector<Eigen::Isometry3d> poses;
  std::vector<tracking::PoseGraphEdge> edges;
  {
    std::lock_guard lock(mutex_);
    poses = keyframe_world_;
    edges = edges_;
  }
  const tracking::PoseGraphConfig& graph = config_.loop_closure.graph;
  std::vector<tracking::PoseGraphEdge> added;
  std::size_t rejected = 0;
  // Only a blurred keyframe (blur_scale_px or more at the finest level): its reference edge is
  // then the weak link, colour lying under blur. A sharp keyframe is measured best by its
  // reference: on teddy the longer baselines' edges made sharp keyframes worse.
  const tracking::OdometryFrame::Level& finest = job.prepared.frame->levels().back();
  const double blur_px = finest.fx * job.prepared.angular_rate * job.odometry.exposure;
  const bool sharp = blur_px < job.odometry.blur_scale_px;
  for (const FrameTracker::PreparedKeyframe& earlier : sharp ? decltype(covisible_){} : covisible_) {
    const std::size_t i = earlier.keyframe, j = job.keyframe;
    if (i >= j || std::any_of(edges.begin(), edges.end(), [&](const auto& e) { return e.i == i && e.j == j; })) continue;
    tracking::OdometryConfig odometry = job.odometry;
    odometry.depth_weight = tracking::blur_aware_depth_weight(odometry, *job.prepared.frame, job.prepared.angular_rate,
                                                              earlier.angular_rate);
    const tracking::OdometryResult r =
        tracking::align_rgbd(*earlier.frame, *job.prepared.frame, poses[j].inverse() * poses[i], odometry);
    if (!r.converged) {
      ++rejected;
      continue;
    }
    tracking::PoseGraphEdge edge;
    edge.i = i, edge.j = j;
    edge.T_i_j = r.T_cur_ref.inverse();
    // An alignment far from where the chain puts the pair found another minimum: left out.
    const Eigen::Isometry3d disagreement = (poses[i].inverse() * poses[j]).inverse() * edge.T_i_j;
    if (disagreement.translation().norm() > graph.drift_floor_m ||
        Eigen::AngleAxisd(disagreement.linear()).angle() * 180 / M_PI > graph.drift_floor_deg) {
      ++rejected;
      continue;
    }
    edge.information = edge_information(r.information);
    added.push_back(edge);
  }
  covisible_.push_back(job.prepared);
  covisible_.back().keyframe = job.keyframe;
  // Its reference among them already has its edge: `wanted` besides it.
  while (covisible_.size() > static_cast<std::size_t>(wanted) + 1) covisible_.pop_front();
  {
    std::lock_guard lock(mutex_);
    totals_.covisible_edges += added.size();
    totals_.covisible_rejected += rejected;
  }
  if (added.empty()) return;
  edges.insert(edges.end(), added.begin(), added.end());
  std::size_t oldest = job.keyframe;
  for (const FrameTracker::PreparedKeyframe& k : covisible_) oldest = std::min(oldest, k.keyframe);
  const std::vector<Eigen::Isometry3d> solved = solve_window(poses, edges, oldest, graph);
  std::vector<Eigen::Isometry3d> mapper_corrections;
  {
    std::lock_guard lock(mutex_);
    edges_.insert(edges_.end(), added.begin(), added.end());
    mapper_corrections = move_keyframes(poses, solved);
  }
  mapper_.correct_keyframes(mapper_corrections);
}

mapping::Vignetting SlamSystem::vignetting() const {
  std::lock_guard lock(mutex_);
  return mapper_.vignetting();
}

void SlamSystem::rethrow_mapping_error() {
  std::lock_guard lock(mutex_);
  if (error_) std::rethrow_exception(error_);
}

double SlamSystem::map_keyframe(const KeyframeJob& job) {
  const auto start = std::chrono::steady_clock::now();
  mapper_keyframes_.push_back(job.keyframe);  // the mapper numbers keyframes in the order added
  const mapping::MappingStats stats = mapper_.add_keyframe(job.frame, job.T_world_cam.inverse());
  if (config_.loop_closure.enabled && config_.front_end == "odometry") close_loops(job);
  if (config_.front_end == "odometry") link_covisible(job);
  auto snapshot = std::make_shared<const splat::Gaussians>(mapper_.map());
  const auto poses = mapper_.keyframe_poses();
  const double ms = ms_since(start);
  std::lock_guard lock(mutex_);
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

namespace {
// The first frame seeds the map from its depth: one with less than this fraction of its pixels
// measured (a covered lens, a sensor still starting) is skipped, and the next one tried.
constexpr double kMinSeedDepthFraction = 0.01;

double measured_fraction(const splat::RgbdFrame& frame) {
  std::size_t measured = 0;
  for (float z : frame.depth) measured += z > 0 && std::isfinite(z);
  return frame.depth.empty() ? 0 : static_cast<double>(measured) / static_cast<double>(frame.depth.size());
}
}  // namespace

FrameRecord SlamSystem::process(const splat::RgbdFrame& frame, bool held_out) {
  rethrow_mapping_error();
  apply_tracker_correction();
  FrameRecord record;
  const double measured = tracker_.started() ? 1.0 : held_out ? 0.0 : measured_fraction(frame);
  if (measured < kMinSeedDepthFraction) {
    record.timestamp = frame.timestamp;
    record.tracked = false;
    record.held_out = held_out;
    record.reason = held_out ? "a held-out frame before the first keyframe"
                             : "waiting for a first frame with depth: " + std::to_string(100 * measured) +
                                   "% of its pixels are measured";
    std::lock_guard lock(mutex_);
    frames_.push_back({kNoKeyframe, Eigen::Isometry3d::Identity(), false, false, held_out, {}});
    record.gaussians = 0;
    return record;
  }
  if (!tracker_.started()) {
    record.timestamp = frame.timestamp;
    record.keyframe = true;
    tracker_.start(frame);
  } else {
    // Threaded, the odometry may track before the first keyframe is mapped, on an empty map.
    const std::shared_ptr<const splat::Gaussians> snapshot = this->map();
    const splat::Gaussians& map = *snapshot;
    record = tracker_.track(map, frame, [this](std::size_t k) {
      std::lock_guard lock(mutex_);
      return keyframe_world_[k];
    });
    if (!record.tracked && !held_out && config_.loop_closure.enabled && config_.front_end == "odometry") {
      // Lost even against the recent keyframes: look for the frame among all of them.
      const tracking::PlaceFeatures features = tracking::extract_place_features(frame, config_.loop_closure.places);
      if (const std::optional<Placement> found = place(thumbnail(frame), features, [](std::size_t) { return true; })) {
        {
          std::lock_guard lock(mutex_);
          record.T_world_cam = splat::orthonormalized(keyframe_world_[found->keyframe] * found->T_keyframe_frame);
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
      tracker_.refine_keyframe(map, frame, record);
    }
  }
  // What mapping leaves out of this frame: where moving objects stand.
  const MovingMask moving = record.moving_share > 0 ? MovingMask::arrivals(tracker_.moving_labels(),
                                                                           frame.width() / tracker_.moving_factor(),
                                                                           tracker_.moving_factor())
                                                    : MovingMask{};
  std::optional<KeyframeJob> job;
  {
    std::lock_guard lock(mutex_);
    if (record.keyframe) {
      job = KeyframeJob{frame, record.T_world_cam, keyframe_world_.size(), {}, {}};
      moving.apply(job->frame);
      if (record.reference != FrameRecord::kNoReference && record.reference < keyframe_world_.size()) {
        // The odometry edge: this keyframe as measured from its reference.
        tracking::PoseGraphEdge edge;
        edge.i = record.reference, edge.j = keyframe_world_.size();
        edge.T_i_j = keyframe_world_[record.reference].inverse() * record.T_world_cam;
        edge.information = edge_information(record.information);
        edges_.push_back(edge);
      }
      keyframe_world_.push_back(record.T_world_cam);
    }
  }
  if (job && job->keyframe > 0) tracker_.keyframe_added(record, job->keyframe);
  if (job && config_.front_end == "odometry") {
    job->prepared = tracker_.newest_reference();
    job->odometry = tracker_.odometry_config();
  }
  if (threaded_ && !thread_.joinable()) thread_ = std::thread([this] { mapping_loop(); });
  // The render front end tracks against the map: the first keyframe seeds it before anything
  // is tracked. The odometry needs no map, so threaded it maps even the first in the background.
  const bool map_now = !threaded_ || (job && job->keyframe == 0 && config_.front_end == "render");
  if (job && map_now) {
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
  // Relative to the keyframe as known now (sequential: after mapping moved it).
  frames_.push_back({keyframe, record.keyframe ? Eigen::Isometry3d::Identity() : keyframe_world_[keyframe].inverse() * record.T_world_cam,
                     record.tracked, record.keyframe, held_out, moving});
  record.held_out = held_out;
  record.gaussians = map_->size();
  return record;
}

SlamSystem::State SlamSystem::state() {
  wait_for_mapping();
  std::lock_guard lock(mutex_);
  State s{tracker_.state(), mapper_.state(), mapper_keyframes_, keyframe_world_, frames_, totals_,
          edges_,           loop_events_,     tracker_correction_, {}, {}};
  for (const FrameTracker::PreparedKeyframe& k : covisible_) {
    s.covisible.push_back(k.keyframe);
    s.covisible_rates.push_back(k.angular_rate);
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
    return load(keyframe_frame[number]);
  };
  for (const tracking::PoseGraphEdge& e : s.edges) {
    if (e.i >= keyframe_frame.size() || e.j >= keyframe_frame.size()) inconsistent("a pose graph edge names a keyframe that does not exist");
  }
  if (s.covisible_rates.size() != s.covisible.size() ||
      s.covisible.size() > static_cast<std::size_t>(config_.loop_closure.covisible_keyframes) + 1) {
    inconsistent(std::to_string(s.covisible.size()) + " covisible keyframes with " + std::to_string(s.covisible_rates.size()) +
                 " rates");
  }
  for (std::size_t k = 0; k < s.covisible.size(); ++k) {
    // Prepared as tracking prepares a reference it restores (tracker_.restore).
    covisible_.push_back({std::make_shared<const tracking::OdometryFrame>(keyframe(s.covisible[k]), config_.odometry),
                          s.covisible[k], s.covisible_rates[k]});
  }
  tracker_.restore(s.tracker, keyframe);
  std::lock_guard places_lock(places_mutex_);
  for (std::size_t k : s.mapper_keyframes) {
    const splat::RgbdFrame frame = keyframe(k);
    places_.add(k, tracking::extract_place_features(frame, config_.loop_closure.places));
    thumbnails_.emplace_back(k, thumbnail(frame));
  }
  mapper_.restore(std::move(s.mapper), [&](std::size_t number) {
    if (number >= s.mapper_keyframes.size()) inconsistent("mapper keyframe " + std::to_string(number) + " does not exist");
    return keyframe(s.mapper_keyframes[number]);
  });
  std::lock_guard lock(mutex_);
  mapper_keyframes_ = std::move(s.mapper_keyframes);
  keyframe_world_ = std::move(s.keyframe_world);
  frames_ = std::move(s.frames);
  totals_ = s.totals;
  edges_ = std::move(s.edges);
  loop_events_ = std::move(s.loop_events);
  tracker_correction_ = s.tracker_correction;
  map_ = std::make_shared<const splat::Gaussians>(mapper_.map());
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
