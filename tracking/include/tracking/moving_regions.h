// Moving objects found without a model: after a frame is aligned to its reference keyframe, the
// reference's surfaces are warped into the frame, and where the frame's depth disagrees with them
// by more than the sensor's noise over a whole region, something moved. Such regions are left
// out of tracking (the frame is then aligned again) and of mapping.
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "tracking/rgbd_odometry.h"

namespace tracking {

struct MovingConfig {
  bool enabled = true;
  // Regions are found at the finest pyramid level at most this wide (the coarsest if none is):
  // 160 px found the generated walking person as well as 320 px, for a quarter of the cost.
  int max_width = 160;
  // A pixel has changed where its depth lies in front of (or behind) every reference surface
  // warped into its 3x3 neighbourhood by more than min_change + noise_sigmas x the sensor
  // noise (OdometryConfig::depth_noise z^2): the neighbourhood keeps depth edges from counting.
  double min_change = 0.05;  // metres
  double noise_sigmas = 6;
  // Regions (4-connected) with fewer changed pixels than this share of the image are noise, or
  // have stopped moving; half of it is enough for a region that continues one (the previous
  // frame's, or a moving surface of the reference).
  double min_region = 0.004;
  // Kept regions grow by this many pixels at their level (object outlines have
  // mixed depth).
  int grow_px = 2;
  // The previous frame's regions, grown by this many pixels, are left out of the first
  // alignment of the next frame, before its own are found.
  int prior_grow_px = 3;
  void validate(const std::string& prefix = "MovingConfig.") const;
};

// The pyramid level (index into OdometryFrame::levels(), coarsest first) regions are found at.
std::size_t moving_level(const OdometryFrame& frame, const MovingConfig& config);

// Per pixel of that level.
enum MovingLabel : uint8_t {
  kStaticPixel = 0,
  kArrived = 1,  // something stands in front of the static scene: a moving object here now
  kLeft = 2,     // the scene is seen behind where the reference saw a surface: an object left
  kOutline = 3,  // around a region (mixed depth): left out like kArrived, never a moving surface
};

// What splat::RgbdFrame::ignore holds for moving regions: a reference frame's kMovingSurface
// pixels are the moving surfaces of moving_regions(); kOutlineIgnored pixels are merely ignored.
inline constexpr uint8_t kOutlineIgnored = 1, kMovingSurface = 2;

// The labels of `current`'s moving_level() ([H, W]) given its pose relative to `reference`.
// `previous`: the last frame's labels (same size) or empty. Surfaces the reference ignores as
// kMovingSurface are moving ones: a pixel at or in front of one continues its region (kArrived), which is kept
// as long as enough of it keeps changing against the static surfaces (the object still moves).
std::vector<uint8_t> moving_regions(const OdometryFrame& reference, const OdometryFrame& current,
                                    const Eigen::Isometry3d& T_cur_ref, const OdometryConfig& odometry,
                                    const MovingConfig& config, std::span<const uint8_t> previous = {});

// `labels` (width x height) grown by `pixels` (kOutline where they spread; a pixel keeps its own
// label). Throws splat::Error if there are not width x height labels.
std::vector<uint8_t> grow_regions(std::span<const uint8_t> labels, int width, int height, int pixels);

}  // namespace tracking
