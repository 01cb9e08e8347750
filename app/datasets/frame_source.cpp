#include "datasets/frame_source.h"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <fstream>
#include <mutex>
#include <thread>
#include <utility>

#include "io/file_error.h"
#include "splat/error.h"

namespace app {
namespace {

using Clock = std::chrono::steady_clock;

// One-slot mailbox shared by both sources: put() replaces an untaken frame (a drop).
class Mailbox {
 public:
  void put(ArrivedFrame frame) {
    {
      std::lock_guard lock(mutex_);
      if (slot_) ++dropped_;
      slot_ = std::move(frame);
    }
    ready_.notify_one();
  }
  std::optional<ArrivedFrame> take(std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    ready_.wait_for(lock, timeout, [&] { return slot_.has_value() || closed_; });
    std::optional<ArrivedFrame> out = std::move(slot_);
    slot_.reset();
    if (out) ++delivered_;
    lock.unlock();
    taken_.notify_all();
    return out;
  }
  // Waits until the slot is empty (its frame taken) or `stop`; false if stopped.
  bool wait_until_taken(const std::atomic<bool>& stop) {
    std::unique_lock lock(mutex_);
    while (slot_ && !stop) taken_.wait_for(lock, std::chrono::milliseconds(20));
    return !stop;
  }
  void close() {
    {
      std::lock_guard lock(mutex_);
      closed_ = true;
    }
    ready_.notify_all();
  }
  bool finished() const {
    std::lock_guard lock(mutex_);
    return closed_ && !slot_;
  }
  void count_drop() {
    std::lock_guard lock(mutex_);
    ++dropped_;
  }
  std::size_t delivered() const {
    std::lock_guard lock(mutex_);
    return delivered_;
  }
  std::size_t dropped() const {
    std::lock_guard lock(mutex_);
    return dropped_;
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable ready_, taken_;
  std::optional<ArrivedFrame> slot_;
  bool closed_ = false;
  std::size_t delivered_ = 0, dropped_ = 0;
};

// A producer thread feeding a mailbox; stopped and joined on destruction.
class ThreadedSource : public FrameSource {
 public:
  ~ThreadedSource() override { stop_and_join(); }
  std::optional<ArrivedFrame> next(std::chrono::milliseconds timeout) override {
    rethrow();
    return mailbox_.take(timeout);
  }
  bool finished() const override { return mailbox_.finished(); }
  void stop() override { stop_and_join(); }
  std::size_t delivered() const override { return mailbox_.delivered(); }
  std::size_t dropped() const override { return mailbox_.dropped(); }

 protected:
  void start() {
    thread_ = std::thread([this] {
      try {
        produce();
      } catch (...) {
        std::lock_guard lock(error_mutex_);
        error_ = std::current_exception();
      }
      mailbox_.close();
    });
  }
  void stop_and_join() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  // Sleeps until `deadline` unless stopped; false if stopped.
  bool sleep_until(Clock::time_point deadline) {
    while (!stop_ && Clock::now() < deadline) {
      std::this_thread::sleep_for(
          std::min<Clock::duration>(deadline - Clock::now(), std::chrono::milliseconds(20)));
    }
    return !stop_;
  }
  virtual void produce() = 0;

  Mailbox mailbox_;
  std::atomic<bool> stop_{false};

 private:
  void rethrow() {
    std::lock_guard lock(error_mutex_);
    if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
  }
  std::thread thread_;
  std::mutex error_mutex_;
  std::exception_ptr error_;
};

class ReplaySource final : public ThreadedSource {
 public:
  ReplaySource(Dataset dataset, double speed) : dataset_(std::move(dataset)), speed_(speed) {
    if (!(speed_ > 0) && speed_ != kEveryFrame)
      throw splat::Error("replay speed " + std::to_string(speed) + ": expected > 0");
    start();
  }
  ~ReplaySource() override { stop_and_join(); }
  const splat::Camera& intrinsics() const override { return dataset_.intrinsics; }
  std::shared_ptr<const Undistortion> undistortion() const override {
    return dataset_.undistortion;
  }
  std::string describe() const override {
    if (speed_ == kEveryFrame) return dataset_.root.string() + " replayed frame by frame (none dropped)";
    return dataset_.root.string() + " replayed at " + std::to_string(speed_).substr(0, 4) +
           "x its recorded rate";
  }

 private:
  void produce() override {
    const auto& entries = dataset_.entries;
    if (entries.empty()) return;
    if (speed_ == kEveryFrame) {
      for (std::size_t i = 0; i < entries.size(); ++i) {
        ArrivedFrame frame{dataset_.load(i), {}, entries[i].T_world_cam_truth};
        if (!mailbox_.wait_until_taken(stop_)) return;
        frame.arrived = Clock::now();
        mailbox_.put(std::move(frame));
      }
      return;
    }
    const Clock::time_point t0 = Clock::now();
    const double first = entries.front().timestamp;
    auto due = [&](std::size_t i) {
      return t0 + std::chrono::duration_cast<Clock::duration>(
                      std::chrono::duration<double>((entries[i].timestamp - first) / speed_));
    };
    for (std::size_t i = 0; i < entries.size(); ++i) {
      if (!sleep_until(due(i))) return;
      // The camera has already produced the next frame: this one was never seen.
      if (i + 1 < entries.size() && Clock::now() >= due(i + 1)) {
        mailbox_.count_drop();
        continue;
      }
      mailbox_.put({dataset_.load(i), Clock::now(), entries[i].T_world_cam_truth});
    }
  }

  Dataset dataset_;
  double speed_;
};

class WatchSource final : public ThreadedSource {
 public:
  WatchSource(std::filesystem::path dir, WatchOptions options)
      : dir_(std::move(dir)), options_(std::move(options)) {
    if (!std::filesystem::is_directory(dir_)) fail(dir_, "watched folder does not exist");
    dataset_.format = "watched";
    dataset_.root = dir_;
    dataset_.depth_scale = options_.depth_scale;
    if (options_.intrinsics.empty()) {
      if (!std::filesystem::exists(dir_ / "intrinsics.txt")) {
        fail(dir_ / "intrinsics.txt", "missing (expected 'fx fy cx cy'); or pass --intrinsics");
      }
      splat::Camera camera;
      const LensDistortion distortion = read_intrinsics_file(camera, dir_ / "intrinsics.txt");
      options_.intrinsics = intrinsics_text(camera, distortion);
    }
    start();
  }
  ~WatchSource() override { stop_and_join(); }
  const splat::Camera& intrinsics() const override {
    std::lock_guard lock(intrinsics_mutex_);
    return dataset_.intrinsics;
  }
  std::shared_ptr<const Undistortion> undistortion() const override {
    std::lock_guard lock(intrinsics_mutex_);
    return dataset_.undistortion;
  }
  std::string describe() const override { return "frames written into " + dir_.string(); }

 private:
  // Pairs present in both rgb/ and depth/ named after the last one taken, in name order (the
  // driver may delete consumed files; nothing here grows with the stream's length).
  std::vector<std::string> new_pairs() {
    std::vector<std::string> names;
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(dir_ / "rgb", ec)) {
      const auto& p = e.path();
      if (p.extension() != ".png" || p.stem().string() <= last_) continue;
      if (std::filesystem::exists(dir_ / "depth" / p.filename()))
        names.push_back(p.stem().string());
    }
    std::sort(names.begin(), names.end());
    return names;
  }

  void produce() override {
    Clock::time_point last_new = Clock::now();
    while (!stop_) {
      const std::vector<std::string> names = new_pairs();
      for (const std::string& name : names) {
        last_ = name;
        ++taken_;
        DatasetEntry entry;
        entry.timestamp = stem_number(name).value_or(static_cast<double>(taken_ - 1) / 30.0);
        entry.rgb = dir_ / "rgb" / (name + ".png");
        entry.depth = dir_ / "depth" / (name + ".png");
        if (dataset_.entries.empty()) {
          std::lock_guard lock(intrinsics_mutex_);
          set_camera(dataset_, options_.intrinsics, entry.rgb);
          const ColorCameraChoice color = parse_color_camera(options_.color_camera);
          if (color.kind == ColorCameraChoice::kGiven) set_color_camera(dataset_, color);
        }
        dataset_.entries = {entry};
        mailbox_.put({dataset_.load(0), Clock::now(), std::nullopt});
        if (options_.every_frame && !mailbox_.wait_until_taken(stop_)) return;
        last_new = Clock::now();
      }
      if (names.empty()) {
        if (std::filesystem::exists(dir_ / "END")) return;
        if (std::chrono::duration<double>(Clock::now() - last_new).count() > options_.idle_timeout)
          return;
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
    }
  }

  std::filesystem::path dir_;
  WatchOptions options_;
  Dataset dataset_;
  std::string last_;  // name of the last pair taken
  std::size_t taken_ = 0;
  mutable std::mutex intrinsics_mutex_;
};

}  // namespace

std::unique_ptr<FrameSource> make_replay_source(Dataset dataset, double speed) {
  return std::make_unique<ReplaySource>(std::move(dataset), speed);
}

std::unique_ptr<FrameSource> make_watch_source(const std::filesystem::path& dir,
                                               const WatchOptions& options) {
  return std::make_unique<WatchSource>(dir, options);
}

}  // namespace app
