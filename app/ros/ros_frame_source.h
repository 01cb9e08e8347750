// The frames gslam_ros tracks: colour + depth message pairs as the subscriber hands them over,
// decoded when tracking takes them. Up to `queue_size` pairs wait; a pair arriving at a full queue
// pushes out the oldest (a drop), so with 1 tracking always takes the newest frame, as `gslam
// live` does with a camera. Pairs wait until the camera is known (the ~intrinsics parameter or
// the first CameraInfo).
#pragma once
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "datasets/frame_source.h"
#include "datasets/lens_distortion.h"
#include "ros/ros_connection.h"

namespace app {

class RosFrameSource final : public FrameSource {
 public:
  // `intrinsics` "fx,fy,cx,cy[,k1,k2,p1,p2,k3]" (the size comes with the first frame) or empty for
  // CameraInfo (its plumb_bob distortion too); distorted frames are undistorted as they are taken;
  // depth_scale 0: by the depth encoding. `alive` says whether ROS is still running.
  RosFrameSource(std::string topics, const std::string& intrinsics, double depth_scale, int queue_size,
                 std::function<bool()> alive);

  // Called by the subscriber (roscpp's threads).
  void add(ros1::RgbdMessages messages);
  void set_camera_info(const RosCameraInfo& info);

  std::optional<ArrivedFrame> next(std::chrono::milliseconds timeout) override;
  bool finished() const override { return !alive_(); }
  void stop() override;
  std::size_t delivered() const override;
  std::size_t dropped() const override;
  const splat::Camera& intrinsics() const override;
  std::shared_ptr<const Undistortion> undistortion() const override;
  std::string describe() const override { return topics_; }

  std::string frame_id() const;  // the last frame taken's header.frame_id
  double depth_scale() const;    // as the parameter, or the last depth encoding's convention

 private:
  const std::string topics_;
  const std::string fixed_intrinsics_;
  const double fixed_depth_scale_;
  const std::size_t queue_size_;
  const std::function<bool()> alive_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<ros1::RgbdMessages> queue_;
  std::optional<RosCameraInfo> info_;
  splat::Camera camera_;  // zero until a frame is taken; the pinhole camera frames come out in
  std::shared_ptr<const Undistortion> undistortion_;  // set where the lens distorts
  std::string frame_id_;
  double depth_scale_ = 0;
  bool stopped_ = false;
  std::size_t delivered_ = 0, dropped_ = 0;
};

}  // namespace app
