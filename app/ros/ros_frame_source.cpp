#include "ros/ros_frame_source.h"

#include "datasets/dataset.h"
#include "datasets/ros_image_decode.h"
#include "splat/error.h"

namespace app {

RosFrameSource::RosFrameSource(std::string topics, const std::string& intrinsics, double depth_scale,
                               int queue_size, std::function<bool()> alive)
    : topics_(std::move(topics)),
      fixed_intrinsics_(intrinsics),
      fixed_depth_scale_(depth_scale),
      queue_size_(static_cast<std::size_t>(queue_size)),
      alive_(std::move(alive)) {
  if (queue_size < 1) throw splat::Error("~queue_size " + std::to_string(queue_size) + ": expected >= 1");
  if (depth_scale < 0) throw splat::Error("~depth_scale " + std::to_string(depth_scale) + ": expected >= 0");
  if (!intrinsics.empty()) apply_intrinsics(camera_, intrinsics);  // checked now, sized by the first frame
  camera_ = {};
}

void RosFrameSource::add(ros1::RgbdMessages messages) {
  {
    std::lock_guard lock(mutex_);
    if (stopped_) return;
    if (queue_.size() == queue_size_) {
      queue_.pop_front();
      ++dropped_;
    }
    queue_.push_back(std::move(messages));
  }
  ready_.notify_one();
}

void RosFrameSource::set_camera_info(const RosCameraInfo& info) {
  {
    std::lock_guard lock(mutex_);
    if (info_) return;  // the camera of a map does not change
    info_ = info;
  }
  ready_.notify_one();
}

std::optional<ArrivedFrame> RosFrameSource::next(std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  const bool known = !fixed_intrinsics_.empty();
  if (!ready_.wait_for(lock, timeout, [&] { return !queue_.empty() && (known || info_); })) return std::nullopt;
  ros1::RgbdMessages m = std::move(queue_.front());
  queue_.pop_front();
  ++delivered_;
  if (camera_.width == 0) {  // the first frame: the camera, sized as its images
    // Built aside and kept only whole: a camera that fails leaves the source as it was.
    splat::Camera camera;
    LensDistortion distortion;
    if (known) {
      distortion = apply_intrinsics(camera, fixed_intrinsics_);
    } else {
      const auto& k = info_->k;
      camera.fx = k[0], camera.fy = k[4], camera.cx = k[2], camera.cy = k[5];
      if (!(camera.fx > 0 && camera.fy > 0)) {
        throw splat::Error(
            "rgb/camera_info: K has fx " + std::to_string(camera.fx) + ", fy " +
            std::to_string(camera.fy) +
            " (an uncalibrated camera?): set ~intrinsics fx,fy,cx,cy[,k1,k2,p1,p2,k3]");
      }
      distortion = lens_distortion_from_ros(info_->distortion_model, info_->d, "rgb/camera_info");
    }
    camera.width = static_cast<int>(m.colour.width);
    camera.height = static_cast<int>(m.colour.height);
    camera.validate("rgb/image");
    std::shared_ptr<const Undistortion> undistortion;
    if (distortion.any()) {
      undistortion = std::make_shared<const Undistortion>(camera, distortion, "rgb/camera_info");
      camera = undistortion->camera();
    }
    camera_ = camera;
    undistortion_ = std::move(undistortion);
  }
  frame_id_ = m.frame_id;
  depth_scale_ = fixed_depth_scale_ > 0 ? fixed_depth_scale_ : default_depth_scale(m.depth);
  const splat::Camera camera = camera_;
  const std::shared_ptr<const Undistortion> undistortion = undistortion_;
  const double depth_scale = depth_scale_;
  lock.unlock();
  ArrivedFrame out{rgbd_frame_from_ros(m.colour, m.depth, camera, depth_scale, "rgb/image (" + m.colour.encoding + ")",
                                       "depth/image (" + m.depth.encoding + ")"),
                   m.arrived, std::nullopt};
  if (undistortion) undistortion->apply(out.frame);
  out.frame.timestamp = m.colour.stamp;
  out.frame.depth_time_offset = m.depth.stamp - m.colour.stamp;  // paired within sync_slop
  return out;
}

void RosFrameSource::stop() {
  std::lock_guard lock(mutex_);
  stopped_ = true;
  dropped_ += queue_.size();  // received, never tracked
  queue_.clear();
}

std::size_t RosFrameSource::delivered() const {
  std::lock_guard lock(mutex_);
  return delivered_;
}

std::size_t RosFrameSource::dropped() const {
  std::lock_guard lock(mutex_);
  return dropped_;
}

const splat::Camera& RosFrameSource::intrinsics() const { return camera_; }

std::shared_ptr<const Undistortion> RosFrameSource::undistortion() const {
  std::lock_guard lock(mutex_);
  return undistortion_;
}

std::string RosFrameSource::frame_id() const {
  std::lock_guard lock(mutex_);
  return frame_id_;
}

double RosFrameSource::depth_scale() const {
  std::lock_guard lock(mutex_);
  return depth_scale_;
}

}  // namespace app
