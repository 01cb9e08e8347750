// The picture `gslam live` shows, composed on the CPU so it is the same with or without a
// window: the map rendered from a follow or orbit camera with the trajectory drawn over it,
// and the current input frame beside it.
#pragma once
#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "splat/camera.h"
#include "splat/gaussians.h"
#include "splat/image.h"
#include "splat/rasterizer.h"

namespace app {

struct LiveViewState {
  std::shared_ptr<const splat::Gaussians> map;  // may be null before the first frame
  std::vector<Eigen::Vector3d> trajectory;      // camera centres, world frame
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();  // the current camera
  splat::Image8 input;                                            // the current colour frame (RGB)
};

// How the map is looked at: behind the current camera (follow), or around the map's centre.
struct ViewCamera {
  bool follow = true;
  double yaw = 0, pitch = 0.5;  // radians, orbit mode
  double zoom = 1;              // orbit distance factor
};

// Layout of the composed picture, in pixels.
inline constexpr int kLiveViewWidth = 960, kLiveViewHeight = 480;
inline constexpr int kMapPanelWidth = 640;
// Colours drawn over the map: trajectory and current camera.
inline constexpr uint8_t kTrajectoryRgb[3] = {255, 255, 0};
inline constexpr uint8_t kCameraRgb[3] = {255, 0, 0};

// Drawing over a composed picture, shared with the map viewer (map_view.h): a pixel rectangle
// [x0, x1) x [y0, y1) that drawing is clipped to, a line of width 2 between two pixel
// positions, and a filled square of side 2 * half + 1 about a pixel.
struct PixelRect {
  int x0, y0, x1, y1;
};
void draw_line(splat::Image8& image, const PixelRect& clip, Eigen::Vector2d a, Eigen::Vector2d b,
               const uint8_t rgb[3]);
void draw_square(splat::Image8& image, const PixelRect& clip, Eigen::Vector2d centre, int half,
                 const uint8_t rgb[3]);

// [kLiveViewHeight, kLiveViewWidth, 3]: the map panel (kMapPanelWidth wide, rendered at half
// resolution and doubled) with the trajectory and current camera, the input frame scaled into
// the top right, and a top view of the trajectory (world x, z) in the bottom right.
splat::Image8 compose_live_view(const LiveViewState& state, const ViewCamera& view,
                                splat::Rasterizer& rasterizer);

}  // namespace app
