#pragma once
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "splat/rgbd_frame.h"

namespace app {

struct DatasetOptions {
  std::string intrinsics;   // "fx,fy,cx,cy" overrides the preset (image size from the files)
  double depth_scale = 0;   // stored value per metre; 0 = the format's default
  int max_frames = 0;       // 0 = all
};

struct DatasetEntry {
  double timestamp = 0;
  std::filesystem::path rgb, depth;
  std::optional<Eigen::Isometry3d> T_world_cam_truth;  // ground truth, camera to world
};

// An RGB-D sequence on disk: entries in time order, loaded one frame at a time.
struct Dataset {
  std::string format;       // "tum", "replica" or "folder"
  std::filesystem::path root;
  splat::Camera intrinsics; // pose unused
  double depth_scale = 5000;
  std::vector<DatasetEntry> entries;
  std::size_t skipped_missing = 0;  // listed entries whose image files do not exist
  std::size_t unmatched = 0;        // colour frames without a depth frame within 0.02 s

  // Reads entry i (colour /255, depth / depth_scale). Throws splat::Error naming the file for
  // unreadable images or a size that does not match the intrinsics.
  splat::RgbdFrame load(std::size_t i) const;
  bool has_ground_truth() const;
};

// Opens a dataset folder, detecting its format: TUM RGB-D (rgb.txt, depth.txt, optional
// groundtruth.txt; intrinsics preset from freiburg1/2/3 in the folder name), Replica as used by
// NICE-SLAM/SplaTAM (results/frame*.jpg|png, results/depth*.png / 6553.5, traj.txt), or the plain
// folder format (README). An unknown camera without --intrinsics is an error, never a guess.
// Intrinsics "fx,fy,cx,cy" with the image size of the colour image `rgb`. Throws splat::Error
// naming the text or the file.
splat::Camera camera_for(const std::string& intrinsics, const std::filesystem::path& rgb);

Dataset open_dataset(const std::filesystem::path& root, const DatasetOptions& options = {});

// TUM's association: each colour frame paired with the nearest unused depth frame within
// max_difference seconds, greedily by smallest difference; returns (colour index, depth index).
std::vector<std::pair<std::size_t, std::size_t>> associate(const std::vector<double>& a,
                                                           const std::vector<double>& b,
                                                           double max_difference = 0.02);

}  // namespace app
