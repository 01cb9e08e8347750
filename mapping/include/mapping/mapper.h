#pragma once
#include <cstdint>
#include <array>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <set>
#include <string>

#include <Eigen/Geometry>

#include "mapping/gaussian_adam.h"
#include "mapping/initialize.h"
#include "mapping/vignetting.h"
#include "splat/rasterizer.h"
#include "splat/resident_map.h"
#include "splat/rgbd_frame.h"
#include "splat/se3.h"

namespace mapping {

struct MapperConfig {
  int resolution_factor = 2;  // keyframes are stored and optimized at 1/factor resolution
  int refine_resolution_factor = 2;  // the same for the final refinement (refine())
  // Adam steps per keyframe. With the odometry the map does not steer tracking, and the final
  // sweep polishes it: 45 -> 20 gave teddy 26.58 -> 27.07 dB, 7-Scenes 24.57 -> 24.55 dB.
  int iterations = 20;
  int window = 4;             // keyframes per optimization window (the new one included)
  std::size_t max_keyframes = 12;  // stored keyframes; the least covisible is dropped beyond
  double color_weight = 0.5, ssim_weight = 0.1, depth_weight = 1.0;
  // The depth weight in the final refinement, where the map is tuned to render the frames: every
  // loosening of depth traded depth error for PSNR along one curve (docs/tuning.md).
  double refine_depth_weight = 0.03;
  // Depth is compared as D/A where the rendered silhouette A exceeds this, as D elsewhere
  // (splat::silhouette_depth_l1_loss). Synthetic room, 30 frames, keyframe poses refined:
  // ATE 0.54 cm comparing D everywhere, 0.31 cm with this.
  double depth_alpha_threshold = 0.95;
  // The same for the final refinement, where poses no longer move and D's push towards opaque
  // surfaces renders better: teddy, 193 frames, PSNR 21.33 dB at 0.95, 22.12 dB at 1 (D everywhere).
  double refine_depth_alpha_threshold = 1.0;
  // Adam's learning rates in the final refinement, relative to the window steps'. Half rate was
  // chosen for 12 full-resolution passes; after the coarse passes full rate renders held-out
  // views better on every sequence of the whole table (docs/tuning.md).
  double refine_learning_rate_scale = 1.0;
  // Pose steps in the final refinement (Adam on se(3), metres and radians); 0 keeps each
  // refined frame where tracking and mapping put it. Moving them fits the map to each frame's
  // view and not to the scene: with the odometry front end it made the trajectory worse on 7 of
  // 8 sequences and held-out views 0.9 dB worse on both real ones (docs/tuning.md).
  double refine_pose_learning_rate = 0, refine_pose_rotation_learning_rate = 0;
  // Adam's step for the camera's vignetting (k1, k2) in the final refinement; 0 leaves it at
  // none. Every step renders through the current vignetting (teddy: +0.5 dB as recorded).
  double refine_vignetting_rate = 2e-3;
  // Keep Gaussians isotropic (one scale, no rotation), as SplaTAM does. Off by default: on the
  // first 60 teddy frames anisotropic maps rendered better (24.6 vs 23.9 dB masked PSNR).
  bool isotropic = false;
  // Densification: seed where the render's silhouette is below this, or where the measured
  // depth is in front of the render by more than depth_error_factor x the median error.
  double densify_alpha = 0.5;
  double depth_error_factor = 10.0;
  // The final refinement's densification (refine()) also seeds uncovered pixels that have no
  // depth measurement, at depth filled in from their neighbours (fill_depth_holes); otherwise
  // the map leaves them empty. Keyframes seed measured pixels alone: their Gaussians are the
  // ones tracking renders. A quarter of teddy's pixels have no depth.
  bool refine_seed_depth_holes = true;
  // Stride at the mapping resolution; seeds at 0.6x the pixel footprint rendered sharper.
  SeedConfig seed{.scale_factor = 0.6};
  // Ghosts: a Gaussian whose centre keyframes (and every frame before the final sweep) see through,
  // the measured depth at its pixel (all of its 3x3 neighbourhood) farther than it by
  // free_space_margin + 2% of the depth, in at least ghost_views views and more than twice as
  // often as it lies on the surface, is pruned: moving objects leave no ghosts.
  int ghost_views = 3;
  double free_space_margin = 0.05;  // metres
  // Pruning after each optimization.
  double prune_opacity = 0.005;
  double prune_max_scale = 0.5;  // metres
  AdamConfig adam;
  // Keyframe poses move with the map in the window optimization (Adam on se(3), left updates,
  // these step sizes in metres and radians); the first keyframe stays fixed as the world
  // frame. 0 keeps every keyframe where tracking put it, which suits the odometry front end
  // (teddy ATE 1.21 -> 0.95 cm, PSNR 25.4 -> 26.6 dB; 7-Scenes 3.48 -> 3.52 cm). With the render
  // front end 2e-4 / 5e-5 helped on teddy and the synthetic room (3.08 -> 1.24, 0.39 -> 0.31 cm).
  double pose_learning_rate = 0, pose_rotation_learning_rate = 0;
  uint32_t random_seed = 1;
  // Where the backend can keep the map on its device (Vulkan), the map, its Adam state and the
  // stored keyframes stay there and each step computes the loss there too: only scalars cross
  // the bus per step. false renders the host's map and computes the loss on the host, as the CPU
  // backend always does (the reference).
  bool device_resident = true;
  // On the device, the final sweep's frames stay stored there after their first visit, up to
  // this many MiB (a 320x240 frame takes 1.2 MiB): the later passes upload nothing. Beyond it a
  // frame is uploaded at each visit, as with 0.
  double sweep_device_cache_mib = 1024;
  // Throws splat::Error naming the first field out of range, as `prefix` + field name.
  void validate(const std::string& prefix = "MapperConfig.") const;
};

// Adam state of one camera pose (se(3), left updates).
struct PoseAdam {
  Eigen::Matrix<double, 6, 1> m = Eigen::Matrix<double, 6, 1>::Zero(), v = m;
  int steps = 0;
};

struct MappingStats {
  std::size_t added = 0, pruned = 0;
  std::size_t ghosts = 0;  // of the pruned, ghosts (MapperConfig::ghost_views)
  int iterations = 0;
  double final_loss = 0;
  std::size_t window = 0;
};

// What a Mapper carries from one keyframe to the next, for checkpoints: all of it but the stored
// keyframes' images, which Mapper::restore takes back from the caller.
struct MapperState {
  splat::Gaussians map;
  GaussianAdam::State adam;
  struct Keyframe {
    std::size_t number = 0;
    Eigen::Isometry3d T_cam_world = Eigen::Isometry3d::Identity();
    PoseAdam pose;
  };
  std::vector<Keyframe> keyframes;  // oldest first
  Vignetting vignetting;
  std::array<double, 2> vignetting_m = {0, 0}, vignetting_v = {0, 0};
  int vignetting_steps = 0;
  std::size_t added = 0;  // keyframes added so far
  std::vector<uint32_t> anchors;  // per Gaussian: the keyframe number that seeded it
  std::vector<uint16_t> seen_through, seen_on;  // per Gaussian: free-space evidence (ghosts)
  std::string rng;        // the window sampler, as std::mt19937's operator<< writes it
};

// The camera's motion while its shutter was open: the twist [v, omega] in the camera's frame
// over the whole exposure, and how many views spread evenly across it a render averages, the
// way the camera recorded the frame (1: the mid-exposure view alone). The host's rasterizer
// renders them; a device-resident map renders the mid-exposure view.
struct ExposureMotion {
  splat::Vector6d twist = splat::Vector6d::Zero();
  int samples = 1;
};

// Builds and refines the map from keyframes with known poses. Memory apart from the map is
// bounded by max_keyframes.
class Mapper {
 public:
  Mapper(splat::Rasterizer& rasterizer, const MapperConfig& config);

  // Adds Gaussians for what the keyframe sees that the map lacks, stores it, optimizes the map
  // over a window of covisible keyframes and prunes. The first keyframe seeds the map.
  MappingStats add_keyframe(const splat::RgbdFrame& frame, const Eigen::Isometry3d& T_cam_world);

  // Final refinement: `iterations` Adam steps of the map on one earlier frame, which the bounded
  // keyframe store may have dropped, given as refinement_frame() made it. Sweeping every frame
  // this way undoes what later windows did to regions they saw poorly. With `densify`, Gaussians
  // are first added where the frame sees what the map lacks (as for a keyframe); no pruning.
  // Where `pose` is given (and refine_pose_learning_rate > 0) the frame's pose moves with the map,
  // with that Adam state; otherwise it stays.
  // `frame_id` names the frame for the device's sweep cache (sweep_device_cache_mib): the same
  // id must always come with the same frame, until release_sweep_frames(). The frame's motion
  // blur is rendered as `motion` says. Adam's rates are `learning_rate_scale` times the window
  // steps' (refine_learning_rate_scale where not given).
  double refine(const splat::RgbdFrame& refinement_frame, Eigen::Isometry3d& T_cam_world,
                PoseAdam* pose, int iterations, bool densify = false,
                std::optional<std::size_t> frame_id = std::nullopt,
                const ExposureMotion& motion = {},
                std::optional<double> learning_rate_scale = std::nullopt);
  // Frees the device's copies of the sweep's frames.
  void release_sweep_frames();
  // An input frame as refine() takes it: at refine_resolution_factor.
  splat::RgbdFrame refinement_frame(const splat::RgbdFrame& frame) const;
  // Counts a view's evidence for each Gaussian being a ghost (MapperConfig::ghost_views): its
  // centre seen through, or on the measured surface; ignored pixels tell nothing. Keyframes
  // count themselves; the final sweep has every frame (as refinement_frame() made it) counted
  // before it starts and again after its densifying passes, for the Gaussians from `first` on.
  void observe_free_space(const splat::RgbdFrame& frame, const Eigen::Isometry3d& T_cam_world, std::size_t first = 0);
  // Removes transparent, oversized (larger than prune_max_scale, unless `oversized` is false)
  // and ghost Gaussians; returns how many, and how many of them were ghosts.
  struct Pruned {
    std::size_t gaussians = 0, ghosts = 0;
  };
  Pruned prune(bool oversized = true);
  // Moves keyframes, and the Gaussians each seeded, rigidly: keyframe number k (and what it
  // anchors) by world_correction[k] (T_world_new * T_world_old^-1), for every keyframe added so
  // far. Gaussians seeded by the final refinement are anchored to the keyframe last added.
  void correct_keyframes(const std::vector<Eigen::Isometry3d>& world_correction);

  MapperState state() const;
  // Continues from `state` (of a mapper with this configuration): `load(number)` gives keyframe
  // `number` as add_keyframe() was given it. Throws splat::Error on an inconsistent state.
  void restore(MapperState state, const std::function<splat::RgbdFrame(std::size_t number)>& load);

  // The map; with a device-resident map, a whole-map transfer when the device has changed it.
  const splat::Gaussians& map() const;
  std::size_t size() const { return device_ ? device_->size() : map_.size(); }
  bool device_resident() const { return device_ != nullptr; }
  const Vignetting& vignetting() const { return vignetting_; }
  std::size_t keyframes() const { return keyframes_.size(); }
  // The stored keyframes' current poses, each with its number in the order they were added.
  std::vector<std::pair<std::size_t, Eigen::Isometry3d>> keyframe_poses() const;

 private:
  struct Keyframe {
    splat::RgbdFrame frame;  // at the mapping resolution
    Eigen::Isometry3d T_cam_world;
    std::size_t number = 0;  // in the order added; 0 is the world frame
    PoseAdam pose = {};
    ExposureMotion motion = {};  // what a render averages to look like the frame
  };
  // Seeds Gaussians where the frame (at its pose) sees what the map lacks, and with
  // `fill_holes` where it has no depth too; returns how many. On the device the coverage test
  // runs there, against the frame stored under `device_key`.
  std::size_t densify(const splat::RgbdFrame& frame, uint64_t device_key, const Eigen::Isometry3d& T_cam_world,
                      bool fill_holes, std::size_t anchor);
  std::vector<Keyframe*> window_for(Keyframe& newest);
  // One Adam step of the map on a keyframe. Window steps also move the keyframe's pose (but
  // the world frame's); refinement steps use refine_depth_alpha_threshold and move the pose
  // where `pose` is given.
  enum class Step { kWindow, kRefine };
  // `device_key`: where the device stores kf's frame; `rate_scale`: Adam's rates relative to
  // the configured ones.
  double optimize_step(Keyframe& kf, Step step, PoseAdam* pose, uint64_t device_key,
                       double rate_scale);
  // The device key of a frame refine() fits: its sweep-cache key if stored there (or room is
  // left to store it), else the one refine frame's, uploaded now.
  uint64_t store_refinement_frame(const splat::RgbdFrame& frame, std::optional<std::size_t> frame_id);
  // optimize_step's loss on the device map (the target stored under `key`); returns the loss and
  // the pose gradient.
  splat::MappingStepResult device_step(const Keyframe& kf, uint64_t key, Step step,
                                       double rate_scale);
  // optimize_step's loss on the host (the reference), then the map's Adam step.
  splat::MappingStepResult host_step(const Keyframe& kf, Step step, double rate_scale);
  // The free-space test's settings (ghost_views): one place for the host's and the device's.
  splat::ResidentMap::FreeSpaceTest free_space_test() const;
  // Adds one view's free-space verdicts, of the Gaussians from `first` on, to their counts.
  void count_free_space(const std::vector<splat::FreeSpace>& verdicts, std::size_t first);
  // Makes map_ (and with `moments`, the Adam state) the device's; after a host change, pushes
  // them back. Both no-ops without a device map.
  void pull_from_device(bool moments) const;
  void push_to_device();
  // After the device changed its map: the host's copies are stale.
  void device_changed() { host_current_ = host_adam_current_ = means_cached_ = false; }
  // One Adam step of a pose from the loss's pose gradient, at these rates.
  void step_pose(Eigen::Isometry3d& T_cam_world, PoseAdam& adam, const splat::PoseGradient& gradient,
                 double translation_rate, double rotation_rate) const;
  // One Adam step of the vignetting from the loss's gradient (refine_vignetting_rate).
  void step_vignetting(const std::array<double, 2>& gradient);

  splat::Rasterizer& rasterizer_;
  MapperConfig config_;
  // The map: on the host, or a cache of the device's (device_ set), refreshed on demand.
  mutable splat::Gaussians map_;
  mutable GaussianAdam adam_;
  std::unique_ptr<splat::ResidentMap> device_;
  mutable bool host_current_ = true, host_adam_current_ = true;
  std::set<uint64_t> sweep_frames_;  // the sweep's frames stored on the device, by key
  double sweep_frames_mib_ = 0;
  std::vector<float> device_means_;  // the device map's means while means_cached_
  bool means_cached_ = false;
  std::deque<Keyframe> keyframes_;
  Vignetting vignetting_;
  struct {
    std::array<double, 2> m = {0, 0}, v = {0, 0};
    int steps = 0;
  } vignetting_adam_;
  std::size_t added_ = 0;
  std::vector<uint32_t> anchors_;  // per Gaussian, aligned with map_
  // Per Gaussian, aligned with map_: views that saw through its centre, and views whose surface
  // it lies on.
  std::vector<uint16_t> seen_through_, seen_on_;

  std::mt19937 rng_;
};

}  // namespace mapping
