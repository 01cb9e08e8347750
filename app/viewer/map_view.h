// The picture `gslam view` shows: a finished map with the cameras that recorded it, seen from a
// view that the mouse and keys move (orbit, pan, zoom, fly) or from one of the recorded cameras.
// Composed on the CPU like the live view (live_view.h), so it is the same with or without a
// window and is tested without one.
#pragma once
#include <Eigen/Geometry>
#include <optional>
#include <vector>

#include "splat/camera.h"
#include "splat/gaussians.h"
#include "splat/image.h"
#include "splat/rasterizer.h"
#include "viewer/views.h"

namespace app {

// Size of the picture (and the window), in pixels: 4:3, the shape of most RGB-D cameras.
inline constexpr int kMapViewWidth = 800, kMapViewHeight = 600;
// Recorded cameras are drawn as frusta in this colour, the trajectory through them in
// kTrajectoryRgb (live_view.h).
inline constexpr uint8_t kCameraMarkerRgb[3] = {0, 200, 255};
// Frusta drawn at most: more cameras than this are thinned evenly (the trajectory line still
// passes through every one).
inline constexpr int kMaxCameraMarkers = 100;

// A map and the cameras that made it.
struct MapScene {
  splat::Gaussians map;
  std::vector<Eigen::Isometry3d> cameras;         // recorded camera-to-world poses, in order
  std::vector<double> timestamps;                 // seconds, one per camera, or empty
  std::optional<Intrinsics> intrinsics;           // the recorded camera, where known
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();  // world up, unit length
  MapExtent extent;                               // map_extent(map)
};

// Fills `extent` and normalizes `up`. Throws splat::Error for an empty map, a zero or non-finite
// up, or timestamps whose count is neither 0 nor the cameras'.
MapScene make_map_scene(splat::Gaussians map, std::vector<Eigen::Isometry3d> cameras,
                        std::vector<double> timestamps, std::optional<Intrinsics> intrinsics,
                        const Eigen::Vector3d& up);

// Where the map is seen from. Invariant: `pivot` lies on the view's optical axis (+z), in front.
struct MapViewCamera {
  Eigen::Isometry3d T_world_view = Eigen::Isometry3d::Identity();  // camera to world, OpenCV axes
  Eigen::Vector3d pivot = Eigen::Vector3d::Zero();  // what orbit turns about and zoom approaches
  Intrinsics k;     // at the picture's size, kMapViewWidth x kMapViewHeight
  int camera = -1;  // the recorded camera shown; -1 once the view has moved off it
};

// The overview: the map's centre seen from 2.5 times the radius that holds the map and the
// cameras, 25 degrees above the plane normal to `up`, from behind the cameras' mean heading
// (any side for a bare map); fx = 0.8 * width (a 64 degree field of view).
MapViewCamera overview_view(const MapScene& scene);
// Recorded camera i's pose, with its intrinsics scaled to fit the picture (the image centred;
// a picture of another shape shows more around it), or the overview's field of view where the
// scene has no intrinsics. The pivot is on its axis, as far as the map's centre lies along it.
// Throws splat::Error when i is not in [0, cameras).
MapViewCamera recorded_view(const MapScene& scene, int i);

// Moves of the view; each sets `camera` to -1. Pixel amounts are mouse motion in the picture.
// orbit: turns about the pivot, dx about `up` and dy up or down (elevation kept within 85
//   degrees of the horizon), the scene following the mouse; 0.01 radian a pixel.
// pan: moves view and pivot across the view so that the pivot's depth follows the mouse.
// zoom: moves the view towards the pivot by 10% of the distance per step (away for negative
//   steps); it never passes the pivot.
// fly: moves view and pivot by metres: x along the view's right, y along `up`, z along the
//   view's axis.
void orbit_view(MapViewCamera& view, const MapScene& scene, double dx_px, double dy_px);
void pan_view(MapViewCamera& view, double dx_px, double dy_px);
void zoom_view(MapViewCamera& view, const MapScene& scene, double steps);
void fly_view(MapViewCamera& view, const MapScene& scene, const Eigen::Vector3d& right_up_forward);

// The camera the map is rendered with: the view's pose and intrinsics, with every size divided
// by `downsample` (1 or more), and a near plane at 0.5% of the map's radius.
splat::Camera render_camera(const MapViewCamera& view, const MapScene& scene, int downsample = 1);

// [kMapViewHeight, kMapViewWidth, 3]: the map rendered from the view (at 1/downsample of the
// resolution and enlarged, for quick redraws while the view moves) over a dark background, the
// trajectory through the recorded cameras, and a frustum for each of them (at most
// kMaxCameraMarkers, evenly spaced, and the last), 6% as deep as the radius that holds the map
// and the cameras; frusta within three depths of the view (the one shown, its neighbours) are
// left out.
splat::Image8 compose_map_view(const MapScene& scene, const MapViewCamera& view,
                               splat::Rasterizer& rasterizer, int downsample = 1);

}  // namespace app
