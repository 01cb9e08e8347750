// Every setting of the SLAM system in one struct. Each default is written once, at its
// declaration here or in TrackingConfig / MapperConfig; docs/tuning.md holds how they were chosen.
#pragma once
#include <string>

#include "mapping/mapper.h"
#include "tracking/moving_regions.h"
#include "tracking/place_recognition.h"
#include "tracking/pose_graph.h"
#include "tracking/rgbd_odometry.h"
#include "tracking/tracker.h"

namespace app {

// Loop closure (odometry front end): every mapped keyframe is matched against the keyframes at
// least `min_separation` keyframes older (tracking/place_recognition.h); a verified match
// becomes a loop edge of the keyframe pose graph (tracking/pose_graph.h), which is solved, and
// keyframes, their frames and the Gaussians anchored to them move to the solution.
struct LoopClosureConfig {
  bool enabled = true;
  int min_separation = 15;
  // A place match is then refined by dense RGB-D alignment of the two keyframes at this width
  // (each mapped keyframe is kept at it: 300 KiB), which must converge for the loop to count:
  // RANSAC on a few dozen features is off by centimetres, the dense alignment by millimetres.
  int dense_width = 160;
  tracking::PlaceRecognitionConfig places;
  tracking::PoseGraphConfig graph;
  // A loop outside the drift budget waits, rejected, for a detection at most this many keyframes
  // later that agrees with it (tracking::loops_agree); the two are then solved as confirmed.
  int confirm_within = 3;
  // Covisibility (odometry front end, whether loops are closed or not): each mapped keyframe
  // blurred by odometry.blur_scale_px or more is also aligned densely, at the tracking
  // resolution, against this many earlier keyframes besides its reference, the most recent ones,
  // and the pose graph over them is solved again with those edges. 0 (off): keyframes are
  // chained by their reference edges alone until a loop closes. 4 cut the whole table's mean ATE
  // by a sixth with every sequence at or below its chained figure (docs/tuning.md, "Covisibility
  // with colour registered").
  int covisible_keyframes = 4;
};

struct SlamConfig {
  // How frames are tracked: "odometry" (dense RGB-D alignment against the reference keyframe,
  // a few milliseconds a frame whatever the map) or "render" (through the rasterizer against
  // the map, `tracking`; hundreds of milliseconds a frame).
  std::string front_end = "odometry";
  tracking::OdometryConfig odometry;
  // Odometry: moving objects found from the depth disagreeing with the reference keyframe, left
  // out of tracking, of the map's seeds and of its losses.
  tracking::MovingConfig moving;
  tracking::TrackingConfig tracking;
  mapping::MapperConfig mapping;
  // Odometry: a new keyframe's pose refined through the rasterizer with this many iterations
  // at the finest tracking level (0: off).
  int keyframe_render_iterations = 0;
  // Odometry: a frame lost against the newest reference keyframe is retried against this many
  // older ones.
  int recovery_keyframes = 3;
  // Odometry: an alignment that converges with its depth residuals' spread (median-based,
  // OdometryResult::depth_spread) this many times the median of the last frames' has found a
  // wrong pose (a camera carried elsewhere still overlaps its reference somewhere): the frame
  // counts as lost, and recovery and relocalization follow; a relocalization whose alignment
  // fails the same test is refused. The most of a good frame on teddy: 2.2x, on 7-Scenes 1.9x.
  // The median counts as at least the sensor noise (residual_ratio).
  double lost_residual_factor = 10.0;
  // A frame becomes a keyframe every `keyframe_every` frames, or earlier after this much motion
  // since the last keyframe.
  int keyframe_every = 5;
  double keyframe_translation = 0.05;  // metres
  double keyframe_rotation_deg = 5.0;
  // Odometry: or once the frame sees less than this fraction of its reference's points.
  double keyframe_overlap = 0.6;
  // A frame whose tracking failed is retried once from the last pose with this many first-order
  // warm-up steps (TrackingConfig::warmup_iterations), whose basin is wider.
  int retry_warmup_iterations = 20;
  // After the last frame (offline runs) the map is swept over the tracked frames this many times
  // in shuffled order, `refine_iterations` map steps per visit: the bounded mapping window lets
  // later keyframes degrade what earlier ones saw.
  int refine_passes = 7;
  int refine_iterations = 1;  // more steps per visit at the same rates rendered worse
  // The sweep's visits after its densifying passes stop at this many in all, so a long recording
  // sweeps about as long as a short one (2,400 visits: 2 minutes at 640x480 on 2 cores; teddy and
  // 7-Scenes, 200 frames x 7 passes, stay under it). Further visits go round the frames evenly.
  int refine_max_visits = 2400;
  // Of the passes after the densifying ones, the first this many visit at half the sweep's
  // resolution, with Adam's rates at refine_coarse_learning_rate_scale times the window steps'
  // (mapping.refine_learning_rate_scale for the others): large cheap steps first, fine ones last
  // (a coarse visit costs 57% of one at full sweep resolution; docs/tuning.md). Under
  // refine_max_visits they keep their share of the visits.
  int refine_coarse_passes = 4;
  double refine_coarse_learning_rate_scale = 4.0;
  // Sweep every tracked frame (true) or the keyframes alone: more viewpoints for the same steps.
  bool refine_all_frames = true;
  // The first this many passes also densify each visited frame, covering what no keyframe saw.
  int refine_densify_passes = 1;
  // Blurred frames are rendered as the camera recorded them: the mean of views across the
  // exposure (one per pixel of blur at the sweep's resolution, up to this many), the motion
  // from the trajectory about the frame over the nominal odometry.exposure (tracking's estimate
  // of it was 8.7x that on 7-Scenes, docs/tuning.md). 1: no blur model.
  int refine_blur_samples = 1;
  // Swept frames (at the refinement resolution) stay in memory up to this many MiB; the rest are
  // reloaded on every visit (teddy's 193 frames take 237 MiB; a reload costs 9 ms).
  double refine_cache_mib = 512;
  // Then re-track every refined frame but the first against the final map, from its current
  // pose, with this many Levenberg-Marquardt iterations at the finest tracking level (0: off,
  // as it cost 0.2 frames/s on teddy for a worse ATE).
  int relocalize_iterations = 0;
  // Threaded mapping (live): keyframes skipped while mapping fell behind are kept, up to this
  // many MiB (a 640x480 keyframe takes 4.7 MiB), for SlamSystem::catch_up_mapping() at the end of
  // the stream; beyond it the oldest are dropped for good.
  double mapping_backlog_mib = 512;
  // Sequential runs (reconstruct) mapping on the backend's device (the resident map): a
  // keyframe's optimization runs on a thread of its own while the next frames are tracked, and
  // what depends on it (loop closure, covisibility, the map and keyframe poses tracking sees) is
  // applied when the next keyframe comes, whatever the timing: as repeatable as mapping in turn
  // (bit for bit with the portable reduction), a checkpoint included. Only where tracking never
  // renders (the odometry front end, keyframe_render_iterations 0). The CPU
  // backend maps in turn with tracking: its mapping takes every core, and overlapping it was no
  // faster (docs/vulkan.md). false: in turn everywhere.
  bool overlap_mapping = true;
  LoopClosureConfig loop_closure;

  struct SweepVisits {
    // The first `densifying` visits densify, the `coarse` after them are coarse.
    std::size_t densifying = 0, coarse = 0, total = 0;
  };
  // The final sweep's visits over this many frames (refine_passes, refine_densify_passes,
  // refine_coarse_passes, refine_max_visits).
  SweepVisits sweep_visits(std::size_t frames) const;

  // Throws splat::Error naming the first field out of range ("mapping.window: expected an
  // integer >= 1, got 0"), tracking and mapping fields included.
  void validate() const;
};

}  // namespace app
