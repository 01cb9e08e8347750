#include "app/live_slam.h"

#include <chrono>

namespace app {

LiveSlam::LiveSlam(splat::Rasterizer& tracking_rasterizer, splat::Rasterizer& mapping_rasterizer,
                   const SlamConfig& config)
    : tracker_(tracking_rasterizer, config), mapper_(mapping_rasterizer, config.mapping) {}

LiveSlam::~LiveSlam() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
    pending_.reset();
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void LiveSlam::publish() {
  auto snapshot = std::make_shared<const splat::Gaussians>(mapper_.map());
  std::lock_guard lock(mutex_);
  map_ = std::move(snapshot);
}

std::shared_ptr<const splat::Gaussians> LiveSlam::map() const {
  std::lock_guard lock(mutex_);
  return map_;
}

FrameRecord LiveSlam::process(const splat::RgbdFrame& frame) {
  {
    std::lock_guard lock(mutex_);
    if (error_) std::rethrow_exception(error_);
  }
  if (!tracker_.started()) {
    FrameRecord record;
    record.timestamp = frame.timestamp;
    const auto start = std::chrono::steady_clock::now();
    mapper_.add_keyframe(frame, Eigen::Isometry3d::Identity());
    record.mapping_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    record.keyframe = true;
    tracker_.start(frame.timestamp);
    publish();
    {
      std::lock_guard lock(mutex_);
      ++mapped_;
    }
    thread_ = std::thread([this] { mapping_loop(); });
    record.gaussians = mapper_.map().size();
    return record;
  }
  const std::shared_ptr<const splat::Gaussians> map = this->map();
  FrameRecord record = tracker_.track(*map, frame);
  record.gaussians = map->size();
  if (tracker_.wants_keyframe(record)) {
    record.keyframe = true;
    tracker_.keyframe_added(record.T_world_cam);
    {
      std::lock_guard lock(mutex_);
      if (pending_) ++skipped_;  // mapping fell behind: the newer keyframe replaces it
      pending_ = Pending{frame, record.T_world_cam.inverse()};
    }
    wake_.notify_one();
  }
  return record;
}

void LiveSlam::mapping_loop() {
  for (;;) {
    Pending job;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return stop_ || pending_.has_value(); });
      if (stop_ && !pending_) return;
      job = std::move(*pending_);
      pending_.reset();
      busy_ = true;
    }
    try {
      mapper_.add_keyframe(job.frame, job.T_cam_world);
      publish();
    } catch (...) {
      std::lock_guard lock(mutex_);
      error_ = std::current_exception();
    }
    {
      std::lock_guard lock(mutex_);
      busy_ = false;
      ++mapped_;
    }
    idle_.notify_all();
  }
}

void LiveSlam::finish() {
  {
    std::unique_lock lock(mutex_);
    idle_.wait(lock, [&] { return !pending_ && !busy_; });
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  std::lock_guard lock(mutex_);
  if (error_) std::rethrow_exception(error_);
}

std::size_t LiveSlam::keyframes_mapped() const {
  std::lock_guard lock(mutex_);
  return mapped_;
}

std::size_t LiveSlam::keyframes_skipped() const {
  std::lock_guard lock(mutex_);
  return skipped_;
}

}  // namespace app
