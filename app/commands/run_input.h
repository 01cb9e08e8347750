// What a run read (summary.json "input": dataset, format, camera, depth units, frames, SLAM
// configuration): written by reconstruct, read back by eval and by reconstruct --resume.
#pragma once
#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "datasets/dataset.h"
#include "slam/slam_config.h"
#include "viewer/views.h"

namespace app {

// The "input" section: where frames came from (`format`: tum, replica, images, rosbag, mcap, or
// watched for a folder a camera driver wrote), their camera and depth units, and the settings of
// the run.
nlohmann::json run_input_json(const std::filesystem::path& input, const std::string& format, const splat::Camera& k,
                              double depth_scale, int max_frames, int test_every, const SlamConfig& config);
// A distorting lens: the raw camera and its distortion ("lens": fx, fy, cx, cy, k1, k2, p1, p2,
// k3), from which the frames were undistorted into "intrinsics".
nlohmann::json lens_json(const Undistortion& undistortion);
// With a ROS recording's topics and --gt-frames ("color_topic", "depth_topic", "gt_frames"), and
// the colour camera the frames were registered with ("color_camera": fx,fy,cx,cy or registered),
// so that eval and --resume load the same colour without estimating it again.
inline nlohmann::json run_input_json(const std::filesystem::path& input, const Dataset& dataset, int max_frames,
                                     int test_every, const SlamConfig& config) {
  nlohmann::json out =
      run_input_json(input, dataset.format, dataset.intrinsics, dataset.depth_scale, max_frames, test_every, config);
  if (!dataset.color_topic.empty()) out["color_topic"] = dataset.color_topic;
  if (!dataset.depth_topic.empty()) out["depth_topic"] = dataset.depth_topic;
  if (!dataset.gt_frames.empty()) out["gt_frames"] = dataset.gt_frames;
  if (dataset.undistortion) out["lens"] = lens_json(*dataset.undistortion);
  out["color_camera"] = ColorResampler::record(dataset.color_registration.get());
  return out;
}

// --test-every N: frame i (counted from 0) is a held-out test view when (i + 1) % N == 0, so the
// first frame, which defines the world, never is. N = 0: none.
inline bool is_held_out(std::size_t frame, int test_every) {
  return test_every > 0 && (frame + 1) % static_cast<std::size_t>(test_every) == 0;
}

struct RecordedInput {
  std::filesystem::path dataset;
  // intrinsics as --intrinsics takes them (the raw camera and its distortion for a distorting
  // lens), depth scale, max frames, a recording's topics
  DatasetOptions options;
  nlohmann::json config;   // null where the run did not record it
  int test_every = 0;      // held-out test views (is_held_out)
};
// Throws splat::Error naming `where` (the file it came from) when a field is missing or malformed.
RecordedInput recorded_input(const nlohmann::json& input, const std::string& where);

// The camera a run recorded in its summary.json ("input"."intrinsics": fx, fy, cx, cy, width,
// height), for render and view. Throws splat::Error naming the file when it cannot be opened;
// nullopt when it records no camera (or is not JSON).
std::optional<Intrinsics> recorded_camera(const std::filesystem::path& summary_path);

}  // namespace app
