// RGB-D SLAM: each frame is tracked against the map; keyframes extend and refine the map; after
// the last frame an offline run may sweep the map over every tracked frame. One object serves
// both ways of running it:
// - sequential (`gslam reconstruct`): each keyframe is mapped inside process(), before the next
//   frame is tracked, so a run is deterministic. With SlamConfig::overlap_mapping (mapping on
//   the device, tracking never rendering) a keyframe's optimization runs on a thread of its own
//   while the next frames are tracked, and the rest of its mapping (loops, covisibility,
//   publishing) runs when the next keyframe comes, on the caller's thread, whatever the timing
//   (a checkpoint carries the keyframe not yet published);
// - threaded (`gslam live`): mapping runs on a thread of its own with its own rasterizer.
//   Keyframes wait in a one-slot queue; a newer keyframe replaces a waiting one (counted as
//   skipped), so tracking never waits for mapping. Skipped keyframes are kept in a backlog
//   bounded in memory (SlamConfig::mapping_backlog_mib), which catch_up_mapping() maps once the
//   stream has ended.
// Frames whose tracking failed never become keyframes, so a bad pose does not corrupt the map.
// The system owns every pose: each frame is held relative to the keyframe it followed, and
// keyframes move as mapping refines them, carrying their frames along, in both modes.
#pragma once
#include <condition_variable>
#include <deque>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include <Eigen/Geometry>

#include "mapping/mapper.h"
#include "slam/back_end.h"
#include "slam/frame_tracker.h"
#include "slam/moving_mask.h"
#include "slam/slam_config.h"
#include "splat/rasterizer.h"
#include "splat/rgbd_frame.h"
#include "tracking/pose_graph.h"

namespace app {

// A loop candidate that place recognition verified, and what the pose graph made of it.
struct LoopEvent {
  std::size_t frame = 0, matched_frame = 0;  // the new keyframe's frame index, the earlier one's
  int inliers = 0;
  double drift_m = 0, drift_deg = 0;  // the error it revealed in the poses before solving
  bool accepted = false;  // false: no dense alignment, or outside the drift budget (a look-alike place)
  // Accepted with the earlier detection at this frame, which it confirmed
  // (BackEnd::Loop::confirms).
  std::optional<std::size_t> confirms_frame;
};

// What mapping did over a run.
struct MappingTotals {
  std::size_t keyframes_mapped = 0;
  std::size_t keyframes_skipped = 0;  // threaded: replaced in the queue, and not (yet) mapped
  std::size_t keyframes_caught_up = 0;  // of those, mapped later by catch_up_mapping()
  std::size_t gaussians_added = 0, gaussians_pruned = 0;
  std::size_t ghosts_pruned = 0;  // of all the run removed, the final sweep's included
  // Covisibility: keyframe-to-keyframe alignments added to the pose graph, and those left out
  // (not converged, or far from where the graph put the pair).
  std::size_t covisible_edges = 0, covisible_rejected = 0;
  std::size_t iterations = 0;
  double last_loss = 0;  // the last window step's loss
  double mapping_ms = 0;
};

class SlamSystem {
 public:
  // Sequential: tracking and mapping take turns on `rasterizer`.
  SlamSystem(splat::Rasterizer& rasterizer, const SlamConfig& config);
  // Threaded: mapping renders with `mapping_rasterizer`, which must differ from
  // `tracking_rasterizer` (each thread renders with its own).
  SlamSystem(splat::Rasterizer& tracking_rasterizer, splat::Rasterizer& mapping_rasterizer,
             const SlamConfig& config);
  ~SlamSystem();  // stops the mapping thread; a keyframe still waiting is dropped
  SlamSystem(const SlamSystem&) = delete;
  SlamSystem& operator=(const SlamSystem&) = delete;

  // Tracks the frame (the first one defines the world frame and seeds the map, synchronously in
  // either mode) and maps it when it becomes a keyframe. A `held_out` frame (a test view) is
  // tracked for its pose but never maps, seeds, becomes a keyframe or joins the final sweep.
  // Rethrows an error of the mapping thread. Takes the frame: a keyframe's goes on to mapping
  // as it is (move it in where the caller is done with it).
  FrameRecord process(splat::RgbdFrame input, bool held_out = false);
  // Threaded: returns once no keyframe waits or is being mapped. Rethrows a mapping error.
  void wait_for_mapping();
  // Waits for mapping, then stops the mapping thread (threaded); nothing in sequential mode.
  void finish();
  // Threaded, after the last process(): maps the skipped keyframes of the backlog, oldest first,
  // at their current poses, calling mapped(done, total) after each; stops early (keeping what
  // it did) once stop() returns true. Returns how many it mapped. Rethrows a mapping error.
  std::size_t catch_up_mapping(const std::function<void(std::size_t, std::size_t)>& mapped = {},
                               const std::function<bool()>& stop = {});
  std::size_t mapping_backlog() const;  // skipped keyframes waiting for catch_up_mapping()

  // The map as last mapped: empty until the first keyframe is, never null; shared, so a reader
  // keeps it.
  std::shared_ptr<const splat::Gaussians> map() const;
  // Camera-to-world poses of every frame processed so far, with the keyframes' corrections.
  std::vector<Eigen::Isometry3d> trajectory() const;
  std::size_t keyframes() const;  // frames that became keyframes (mapped or skipped)
  MappingTotals mapping_totals() const;
  // Whether the map is optimized on the backend's device (Mapper::device_resident).
  bool mapping_on_device() const { return mapper_.device_resident(); }
  // Whether keyframes are optimized while the next frames are tracked (SlamConfig::overlap_mapping).
  bool mapping_overlapped() const { return overlapped_; }
  std::vector<LoopEvent> loop_events() const;
  // The camera's vignetting as the final refinement estimated it (none before). Only the sweep
  // changes it, on refine_map()'s thread: call it on that thread.
  mapping::Vignetting vignetting() const;

  // The frames refine_map() visits, by frame index: the keyframes, or every tracked frame with
  // refine_all_frames.
  std::vector<std::size_t> refine_frames() const;
  struct Refinement {
    std::size_t frames = 0, visits = 0, pruned = 0, ghosts = 0;  // ghosts: of the pruned
    std::size_t blurred = 0;  // frames rendered through the blur model (refine_blur_samples)
    bool stopped = false;  // stop() ended it early
  };
  // The final sweep (SlamConfig::refine_passes) over refine_frames(), each loaded with
  // load(frame index) (the next one read ahead on a thread of its own) and kept while
  // refine_cache_mib allows, in a shuffled order that is the
  // same on every run; the first passes densify (refine_densify_passes). Where
  // MapperConfig::refine_pose_learning_rate > 0 (off by default), visited frames but the first
  // (the world frame) move with the map, and trajectory() returns the moved poses. Then prunes,
  // and re-tracks where relocalize_iterations > 0. Finishes mapping first. Calls
  // visited(done, total) after each visit, and ends the sweep early (keeping what it did) once
  // stop() returns true.
  Refinement refine_map(const std::function<splat::RgbdFrame(std::size_t)>& load,
                        const std::function<void(std::size_t, std::size_t)>& visited = {},
                        const std::function<bool()>& stop = {});

  // A frame's pose relative to the keyframe it followed (or itself); kNoKeyframe for frames
  // skipped while waiting for a first frame with depth (pose: identity, not tracked).
  static constexpr std::size_t kNoKeyframe = static_cast<std::size_t>(-1);
  struct FramePose {
    std::size_t keyframe;
    Eigen::Isometry3d T_keyframe_cam;
    bool tracked, is_keyframe;
    bool held_out = false;
    MovingMask moving;  // left out of mapping, and of the final sweep
    // How the frame's depth was moved to its colour's instant (unsynchronized cameras).
    Eigen::Isometry3d T_colour_depth = Eigen::Isometry3d::Identity();
  };
  // Everything the system carries from one frame to the next, for checkpoints; the keyframes'
  // images excepted, which restore() loads again.
  struct State {
    FrameTracker::State tracker;
    mapping::MapperState mapper;
    std::vector<std::size_t> mapper_keyframes;  // the system's keyframe number per mapper number
    std::vector<Eigen::Isometry3d> keyframe_world;  // T_world_cam per keyframe number
    std::vector<FramePose> frames;              // one per frame processed
    MappingTotals totals;
    BackEnd::State back_end;  // the keyframe pose graph's edges, covisibility's recent keyframes
    std::vector<LoopEvent> loop_events;
    Eigen::Isometry3d tracker_correction = Eigen::Isometry3d::Identity();  // not yet applied
    // Overlapped: the newest keyframe, optimized (it is in `mapper`) but not yet published; the
    // continued run publishes it at the next keyframe, as the run that never stopped does.
    struct Unpublished {
      std::size_t keyframe = 0;  // its number among the system's keyframes
      mapping::MappingStats stats;
      double optimize_ms = 0;
    };
    std::optional<Unpublished> unpublished;
  };
  // The state between two frames (threaded: once mapping is idle).
  State state();
  // Continues from `state` on a system that has processed no frame yet, as if it had processed
  // those frames: `load(i)` gives frame i as process() was given it. Throws splat::Error on a
  // state that does not hold together.
  void restore(State state, const std::function<splat::RgbdFrame(std::size_t)>& load);

 private:
  // Each swept frame's motion over its exposure (SlamConfig::refine_blur_samples), by frame
  // index; frame_at(i) gives frame i as the sweep refines it.
  std::vector<mapping::ExposureMotion> exposure_motions(const std::vector<std::size_t>& frames,
                                                        const std::vector<Eigen::Isometry3d>& T_world_cam,
                                                        const std::function<const splat::RgbdFrame&(std::size_t)>& frame_at) const;
  struct KeyframeJob {
    splat::RgbdFrame frame;
    Eigen::Isometry3d T_world_cam;
    std::size_t keyframe;  // its number among the system's keyframes
    // Odometry with covisibility: the keyframe as tracking prepared it (numbered as `keyframe`: it
    // is tracking's newest reference), and tracking's settings then; empty otherwise. Its pyramid
    // is held weakly: a backlog of keyframes behind mapping would hold 2.4 MiB each at 640x480
    // (tracking_reference() makes it again once tracking has let it go).
    FrameTracker::PreparedKeyframe prepared;  // its frame empty: see pyramid
    std::weak_ptr<const tracking::OdometryFrame> pyramid;
    tracking::OdometryConfig odometry;
  };
  // Odometry with covisibility: gives the job tracking's newest reference (the job's keyframe) and
  // its settings.
  void with_tracking_reference(KeyframeJob& job) const;
  // The job's keyframe as tracking prepared it: tracking's pyramid if it still holds it, else the
  // same made again from the job's frame.
  FrameTracker::PreparedKeyframe tracking_reference(const KeyframeJob& job) const;
  // Maps one keyframe, then publishes the map and the keyframes' moved poses; returns its time.
  double map_keyframe(const KeyframeJob& job);
  // The two halves of map_keyframe: the mapper's optimization (the mapping thread's, or the
  // overlapped one's), then loops, covisibility and publishing, which add their time to
  // `optimize_ms` and return the sum.
  mapping::MappingStats optimize_keyframe(const KeyframeJob& job);
  double publish_keyframe(const KeyframeJob& job, const mapping::MappingStats& stats, double optimize_ms);
  // Overlapped: optimizes `job` on a thread of its own; join_overlapped() waits for it
  // (rethrowing its error); finish_overlapped() joins it, publishes it and moves tracking with
  // the loops it closed, and returns the time that took (0 when none was in flight).
  void start_overlapped(KeyframeJob job);
  void join_overlapped();
  double finish_overlapped();
  // Loop closure for a keyframe just mapped (the mapping thread's), then covisibility: the back
  // end's solutions applied to the keyframes, the map and tracking.
  void close_loops(const KeyframeJob& job);
  void link_covisible(const KeyframeJob& job);
  // The poses of keyframes 0 .. keyframe, which the back end solves for that keyframe's job.
  std::vector<Eigen::Isometry3d> keyframes_up_to(std::size_t keyframe) const;
  // Moves every keyframe (and with them the map and tracking's motion model) from `before`
  // (the poses the graph was solved from) to `solved`; the caller holds mutex_ and calls
  // mapper_.correct_keyframes with what it returns once it has released it.
  std::vector<Eigen::Isometry3d> move_keyframes(const std::vector<Eigen::Isometry3d>& before,
                                                const std::vector<Eigen::Isometry3d>& solved);
  std::size_t frame_of_keyframe(std::size_t keyframe) const;  // caller holds mutex_
  // Applies a correction the mapping thread left for tracking (the caller is tracking). With
  // `frame_begins`, a frame's tracking begins: from here until the frame is added, it is tracked
  // against the keyframes as they are now, whatever mapping moves meanwhile (keyframe_as_tracked).
  void apply_tracker_correction(bool frame_begins = false);
  // A keyframe as the frame being tracked sees it: as it was when its tracking began (the caller
  // holds mutex_).
  const Eigen::Isometry3d& keyframe_as_tracked(std::size_t keyframe) const;
  // Mapping is about to move keyframes (the caller holds mutex_): while a frame is being
  // tracked, the poses it is tracked against are kept first.
  void keep_keyframes_as_tracked();
  void mapping_loop();
  void rethrow_mapping_error();
  Eigen::Isometry3d pose_of(const FramePose& frame) const;  // caller holds mutex_

  const SlamConfig config_;
  splat::Rasterizer& tracking_rasterizer_;
  FrameTracker tracker_;
  mapping::Mapper mapper_;  // the mapping thread's alone while it runs
  BackEnd back_end_;
  const bool threaded_;
  const bool overlapped_;  // sequential, with SlamConfig::overlap_mapping where it applies
  struct InFlight {
    KeyframeJob job;
    std::future<std::pair<mapping::MappingStats, double>> optimized;  // and its time in ms
    std::optional<std::pair<mapping::MappingStats, double>> joined;   // once it has ended
  };
  std::unique_ptr<InFlight> in_flight_;  // overlapped: the keyframe optimized, not yet published
  std::vector<std::size_t> mapper_keyframes_;  // the system's keyframe number per mapper number

  mutable std::mutex mutex_;  // guards everything below
  std::vector<Eigen::Isometry3d> keyframe_world_;  // T_world_cam per keyframe number
  std::vector<FramePose> frames_;
  std::shared_ptr<const splat::Gaussians> map_ = std::make_shared<const splat::Gaussians>();
  MappingTotals totals_;
  std::vector<LoopEvent> loop_events_;
  Eigen::Isometry3d tracker_correction_ = Eigen::Isometry3d::Identity();
  // Threaded: whether a frame is being tracked, and the keyframes as it is tracked against them
  // once mapping has moved them since its tracking began (else none kept).
  bool tracking_frame_ = false;
  std::optional<std::vector<Eigen::Isometry3d>> keyframes_as_tracked_;
  std::optional<KeyframeJob> pending_;
  std::deque<KeyframeJob> backlog_;  // skipped keyframes, oldest first
  double backlog_mib_ = 0;
  bool busy_ = false, stop_ = false;
  std::exception_ptr error_;
  std::condition_variable wake_, idle_;
  std::thread thread_;
};

}  // namespace app
