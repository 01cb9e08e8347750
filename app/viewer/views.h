#pragma once
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "splat/camera.h"
#include "splat/gaussians.h"

namespace app {

// Robust extent of a map: median of the means and the 90th percentile of the distances to it,
// so a few stray splats far away do not move the camera.
struct MapExtent {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 0;
};
MapExtent map_extent(const splat::Gaussians& gaussians);

struct Intrinsics {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;
};
// Limits on what a command line may ask a render for, so memory stays under 1 GiB.
inline constexpr double kMaxRenderPixels = 4096.0 * 4096.0;
inline constexpr int kMaxOrbitViews = 100000;

// Parses "fx,fy,cx,cy,W,H". Throws splat::Error naming the text for anything else.
Intrinsics parse_intrinsics(const std::string& text);
// Parses "WxH" (for example 640x480), at most kMaxRenderPixels.
std::pair<int, int> parse_size(const std::string& text);

// n cameras on a circle around the map's centre at 2.5 map radii, 25 degrees above the plane
// normal to `up`, each looking at the centre; fx = fy = 0.8 * width (a ~64 degree view).
std::vector<splat::Camera> orbit_cameras(const MapExtent& extent, int n, int width, int height,
                                         const Eigen::Vector3d& up);

// Views of a map that a run made, from the run's own camera poses (camera-to-world):
// - camera_up: the world's up as the cameras saw it, the mean of their image-up axes (-y);
// - orbit_at_camera_height: n views on a circle about the map's centre in the plane normal to
//   that up, at the cameras' mean height along it and their mean distance from the centre,
//   looking at the centre, with the run's intrinsics;
// - novel_path: `views` poses along the recorded path, smoothed (a moving average over
//   +-half_window poses), interpolated between the poses and moved by `offset_cam` (metres, in
//   each camera's own axes: x right, y down, z forward), so that every view is one the camera
//   did not take.
Eigen::Vector3d camera_up(const std::vector<Eigen::Isometry3d>& poses);
// As above, about `up` (world frame, made unit) instead of camera_up(poses).
std::vector<splat::Camera> orbit_at_camera_height(const MapExtent& extent, const std::vector<Eigen::Isometry3d>& poses,
                                                  int n, const Intrinsics& k);
std::vector<splat::Camera> orbit_at_camera_height(const MapExtent& extent, const std::vector<Eigen::Isometry3d>& poses,
                                                  int n, const Intrinsics& k, const Eigen::Vector3d& up);

// The world's up direction for a run's map and camera poses (camera-to-world), in the world frame.
struct WorldUp {
  enum class Source { kCameras, kFloorPlane };
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();  // unit
  Source source = Source::kCameras;
  // "cameras" or "floor plane", as summary.json records it.
  const char* source_name() const { return source == Source::kFloorPlane ? "floor plane" : "cameras"; }
};
// Starts from camera_up(poses) and refines it by the floor where the map has one: planes among
// the Gaussians' means (at most kWorldUpMaxPoints of them, evenly strided) are found by RANSAC
// (fixed seed: deterministic), kept when their normal lies within 30 degrees of the cameras' up,
// they hold at least 5% of the means and 80% of the cameras are above them; of those holding at
// least half as many means as the largest, the lowest is the floor, and its least-squares normal
// (pointing to the cameras) is the up. Otherwise the cameras' up. Throws splat::Error when
// there are no poses or they agree on no up direction.
inline constexpr std::size_t kWorldUpMaxPoints = 20000;
WorldUp estimate_world_up(const std::vector<Eigen::Isometry3d>& poses, const splat::Gaussians& map);
std::vector<Eigen::Isometry3d> novel_path(const std::vector<Eigen::Isometry3d>& poses, int views,
                                          const Eigen::Vector3d& offset_cam, int half_window = 8);

// Camera-to-world pose at `eye` looking at `target`, image y pointing against `up` (OpenCV axes).
Eigen::Isometry3d look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, const Eigen::Vector3d& up);

// Camera at `T_world_cam` with the given intrinsics.
splat::Camera make_camera(const Intrinsics& k, const Eigen::Isometry3d& T_world_cam);

}  // namespace app
