#include "ros/ros_node.h"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <deque>
#include <future>
#include <thread>

#include "commands/live_command.h"
#include "commands/run_input.h"
#include "io/slam_config_io.h"
#include "ros/ros_connection.h"
#include "ros/ros_frame_source.h"
#include "splat/error.h"

namespace app {
namespace {

using Clock = std::chrono::steady_clock;

// ---- Parameters: the node's own, then the SLAM settings by the config loader's names.

template <typename T>
void take(const nlohmann::json& v, const std::string& name, T& out) {
  const auto wrong = [&](const char* expected) {
    return splat::Error("~" + name + ": expected " + expected + ", got " + v.dump());
  };
  if constexpr (std::is_same_v<T, bool>) {
    if (!v.is_boolean()) throw wrong("true or false");
    out = v.get<bool>();
  } else if constexpr (std::is_same_v<T, int>) {
    if (!v.is_number_integer()) throw wrong("an integer");
    out = v.get<int>();
  } else if constexpr (std::is_same_v<T, double>) {
    if (!v.is_number()) throw wrong("a number");
    out = v.get<double>();
  } else {
    if (!v.is_string()) throw wrong("a string");
    out = v.get<std::string>();
  }
}

using Setter = std::function<void(RosNodeOptions&, const nlohmann::json&, const std::string&)>;
template <typename T>
Setter field(T RosNodeOptions::*member) {
  return [member](RosNodeOptions& o, const nlohmann::json& v, const std::string& name) {
    if constexpr (std::is_same_v<T, std::filesystem::path>) {
      std::string text;
      take(v, name, text);
      o.*member = text;
    } else {
      take(v, name, o.*member);
    }
  };
}

const std::vector<std::pair<std::string, Setter>>& node_parameters() {
  static const std::vector<std::pair<std::string, Setter>> table = {
      {"out", field(&RosNodeOptions::out)},
      {"overwrite", field(&RosNodeOptions::overwrite)},
      {"config", field(&RosNodeOptions::config)},
      {"backend", field(&RosNodeOptions::backend)},
      {"threads", field(&RosNodeOptions::threads)},
      {"intrinsics", field(&RosNodeOptions::intrinsics)},
      {"depth_scale", field(&RosNodeOptions::depth_scale)},
      {"queue_size", field(&RosNodeOptions::queue_size)},
      {"sync_slop", field(&RosNodeOptions::sync_slop)},
      {"map_frame", field(&RosNodeOptions::map_frame)},
      {"odom_frame", field(&RosNodeOptions::odom_frame)},
      {"camera_frame", field(&RosNodeOptions::camera_frame)},
      {"path_period", field(&RosNodeOptions::path_period)},
      {"cloud_period", field(&RosNodeOptions::cloud_period)},
      {"render_period", field(&RosNodeOptions::render_period)},
      {"render_width", field(&RosNodeOptions::render_width)},
      {"checkpoint_seconds", field(&RosNodeOptions::checkpoint_seconds)},
      {"catch_up", field(&RosNodeOptions::catch_up)},
  };
  return table;
}

struct NodeSetup {
  RosNodeOptions options;
  SlamConfig config;
};

NodeSetup setup_from(const ros1::Parameters& parameters) {
  NodeSetup setup;
  const nlohmann::json settings_names = slam_config_to_json(SlamConfig{});
  nlohmann::json overrides = nlohmann::json::object();
  for (const auto& [name, value] : parameters) {
    const auto& table = node_parameters();
    const auto own = std::find_if(table.begin(), table.end(), [&](const auto& p) { return p.first == name; });
    if (own != table.end()) {
      own->second(setup.options, value, name);
    } else if (settings_names.contains(name.substr(0, name.find('/')))) {
      overrides[nlohmann::json::json_pointer("/" + name)] = value;
    } else {
      std::string names;
      for (const auto& p : table) names += (names.empty() ? "" : ", ") + p.first;
      throw splat::Error("~" + name + ": unknown parameter (the node's are " + names +
                         "; the SLAM settings are those gslam_ros --print-config lists)");
    }
  }
  nlohmann::json settings = slam_config_to_json(load_slam_config(setup.options.config));
  settings.merge_patch(overrides);
  setup.config = slam_config_from_json(settings);
  const RosNodeOptions& o = setup.options;
  for (const auto& [name, period] : {std::pair{"path_period", o.path_period}, {"cloud_period", o.cloud_period},
                                     {"render_period", o.render_period}, {"sync_slop", o.sync_slop}}) {
    if (!(period > 0)) throw splat::Error("~" + std::string(name) + " " + std::to_string(period) + ": expected > 0");
  }
  if (o.render_width < 16 || o.render_width > 4096)
    throw splat::Error("~render_width " + std::to_string(o.render_width) + ": expected 16..4096");
  return setup;
}

// The run's handle on a source that the subscriber shares.
class SharedSource final : public FrameSource {
 public:
  explicit SharedSource(std::shared_ptr<RosFrameSource> source) : source_(std::move(source)) {}
  std::optional<ArrivedFrame> next(std::chrono::milliseconds timeout) override { return source_->next(timeout); }
  bool finished() const override { return source_->finished(); }
  void stop() override { source_->stop(); }
  std::size_t delivered() const override { return source_->delivered(); }
  std::size_t dropped() const override { return source_->dropped(); }
  const splat::Camera& intrinsics() const override { return source_->intrinsics(); }
  std::shared_ptr<const Undistortion> undistortion() const override {
    return source_->undistortion();
  }
  std::string describe() const override { return source_->describe(); }

 private:
  std::shared_ptr<RosFrameSource> source_;
};

// ---- The host: publishes what the run tracks, serves the services, draws the map for RViz.

class RosHost final : public LiveHost {
 public:
  RosHost(ros1::Connection& connection, const RosNodeOptions& options)
      : connection_(connection), options_(options), drawing_rasterizer_(splat::make_cpu_rasterizer({1})) {}
  ~RosHost() override {
    {
      std::lock_guard lock(draw_mutex_);
      closing_ = true;
    }
    draw_wake_.notify_all();
    if (drawer_.joinable()) drawer_.join();
  }

  std::unique_ptr<FrameSource> open_source() override {
    // The subscriber's callbacks share the queue: it outlives the run, which owns only a handle.
    auto source = std::make_shared<RosFrameSource>(connection_.topics(), options_.intrinsics, options_.depth_scale,
                                                   options_.queue_size, [this] { return connection_.ok(); });
    source_ = source;
    ros1::ConnectionOptions c;
    c.map_frame = options_.map_frame;
    c.odom_frame = options_.odom_frame;
    c.camera_frame = options_.camera_frame;
    c.sync_slop = options_.sync_slop;
    c.subscriber_queue = std::max(10, options_.queue_size);
    connection_.start(
        c, [source](ros1::RgbdMessages m) { source->add(std::move(m)); },
        [source](const RosCameraInfo& info) { source->set_camera_info(info); },
        [this](ros1::Request kind) { return request(kind); });
    drawer_ = std::thread([this] { draw_loop(); });
    return std::make_unique<SharedSource>(source);
  }

  // The run has ended: a service call waiting for it is answered now.
  void close() { closed_ = true; }

  nlohmann::json input_json(const splat::Camera& intrinsics, const SlamConfig& config) const override {
    nlohmann::json input = run_input_json(".", "ros", intrinsics, source_ ? source_->depth_scale() : 0, 0, 0, config);
    input["dataset"] = connection_.topics();
    if (source_ && source_->undistortion()) input["lens"] = lens_json(*source_->undistortion());
    return input;
  }

  void tracked(const splat::Camera& camera, const FrameRecord& record,
               const SlamSystem& system) override {
    const std::string frame_id = source_->frame_id();
    if (record.tracked) connection_.publish_pose(record.timestamp, frame_id, record.T_world_cam);
    stamps_.push_back(record.timestamp);
    const Clock::time_point now = Clock::now();
    if (now >= next_path_) {
      next_path_ = now + seconds(options_.path_period);
      const std::vector<Eigen::Isometry3d> poses = system.trajectory();
      std::vector<std::pair<double, Eigen::Isometry3d>> path;
      for (std::size_t i = 0; i < std::min(poses.size(), stamps_.size()); ++i) path.emplace_back(stamps_[i], poses[i]);
      connection_.publish_path(path);
    }
    {
      std::lock_guard lock(draw_mutex_);
      latest_ = Drawable{system.map(), record.T_world_cam, record.timestamp, camera, frame_id};
    }
  }

  void map_changed(std::shared_ptr<const splat::Gaussians> map) override {
    std::lock_guard lock(draw_mutex_);
    if (latest_) latest_->map = std::move(map);
  }

  std::optional<LiveRequest> next_request() override {
    std::lock_guard lock(request_mutex_);
    if (requests_.empty()) return std::nullopt;
    LiveRequest r = std::move(requests_.front());
    requests_.pop_front();
    if (r.kind == LiveRequest::kReset) {  // the run starts over before its next frame
      stamps_.clear();
      connection_.reset_map();
    }
    return r;
  }

 private:
  static Clock::duration seconds(double s) {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
  }

  // A service call (roscpp's thread): waits until the run has served it between two frames.
  std::pair<bool, std::string> request(ros1::Request kind) {
    auto answer = std::make_shared<std::promise<std::pair<bool, std::string>>>();
    std::future<std::pair<bool, std::string>> done = answer->get_future();
    {
      std::lock_guard lock(request_mutex_);
      requests_.push_back({kind == ros1::Request::kSave ? LiveRequest::kSave : LiveRequest::kReset,
                           [answer](bool ok, const std::string& message) { answer->set_value({ok, message}); }});
    }
    // The run serves requests at least every 100 ms; it may have ended meanwhile.
    while (done.wait_for(std::chrono::milliseconds(200)) != std::future_status::ready) {
      if (closed_ || !connection_.ok()) return {false, "gslam_ros is shutting down"};
    }
    return done.get();
  }

  struct Drawable {
    std::shared_ptr<const splat::Gaussians> map;
    Eigen::Isometry3d T_world_cam;
    double stamp;
    splat::Camera camera;
    std::string frame_id;
  };

  // The map's centres for ~map_cloud and its view from the camera for ~render, each at its own
  // period and only while someone subscribes, on a thread of its own (tracking never waits).
  void draw_loop() {
    Clock::time_point next_cloud = Clock::now(), next_render = Clock::now();
    std::shared_ptr<const splat::Gaussians> last_cloud_map;
    while (true) {
      std::optional<Drawable> d;
      {
        std::unique_lock lock(draw_mutex_);
        draw_wake_.wait_until(lock, std::min(next_cloud, next_render), [&] { return closing_; });
        if (closing_) return;
        d = latest_;
      }
      const Clock::time_point now = Clock::now();
      if (!d || !d->map || d->map->empty()) {
        next_cloud = next_render = now + std::chrono::milliseconds(100);
        continue;
      }
      if (now >= next_cloud) {
        next_cloud = now + seconds(options_.cloud_period);
        if (connection_.wants_cloud() && d->map != last_cloud_map) {
          publish_cloud(*d);
          last_cloud_map = d->map;
        }
      }
      if (now >= next_render) {
        next_render = now + seconds(options_.render_period);
        if (connection_.wants_render()) publish_render(*d);
      }
    }
  }

  void publish_cloud(const Drawable& d) {
    constexpr float kShC0 = 0.28209479177387814f;  // the SH DC basis: colour = kShC0 * dc + 0.5
    const splat::Gaussians& g = *d.map;
    const std::size_t stride = g.sh.size() / std::max<std::size_t>(1, g.size());
    std::vector<Eigen::Vector3f> centres(g.size());
    std::vector<std::array<std::uint8_t, 3>> colours(g.size());
    for (std::size_t i = 0; i < g.size(); ++i) {
      centres[i] = Eigen::Vector3f(g.means[3 * i], g.means[3 * i + 1], g.means[3 * i + 2]);
      for (int c = 0; c < 3; ++c) {
        const float v = kShC0 * g.sh[i * stride + std::size_t(c)] + 0.5f;
        colours[i][std::size_t(c)] = static_cast<std::uint8_t>(std::clamp(v, 0.f, 1.f) * 255.f + 0.5f);
      }
    }
    connection_.publish_cloud(d.stamp, centres, colours);
  }

  void publish_render(const Drawable& d) {
    splat::Camera camera = d.camera;
    const double s = static_cast<double>(options_.render_width) / camera.width;
    camera.fx *= s, camera.fy *= s, camera.cx *= s, camera.cy *= s;
    camera.width = options_.render_width;
    camera.height = std::max(1, static_cast<int>(std::lround(d.camera.height * s)));
    camera.T_cam_world = d.T_world_cam.inverse();
    const splat::ForwardResult f = drawing_rasterizer_->forward(*d.map, camera, splat::RenderSettings{});
    std::vector<std::uint8_t> rgb(f.rgb.size());
    for (std::size_t k = 0; k < rgb.size(); ++k)
      rgb[k] = static_cast<std::uint8_t>(std::clamp(f.rgb[k], 0.f, 1.f) * 255.f + 0.5f);
    connection_.publish_render(d.stamp, d.frame_id, camera.width, camera.height, rgb);
  }

  ros1::Connection& connection_;
  const RosNodeOptions options_;
  std::shared_ptr<RosFrameSource> source_;
  std::vector<double> stamps_;  // the run's thread's: one per frame processed
  Clock::time_point next_path_ = Clock::now();
  std::mutex request_mutex_;
  std::deque<LiveRequest> requests_;
  std::atomic<bool> closed_{false};
  std::unique_ptr<splat::Rasterizer> drawing_rasterizer_;
  std::mutex draw_mutex_;
  std::condition_variable draw_wake_;
  std::optional<Drawable> latest_;
  bool closing_ = false;
  std::thread drawer_;
};

bool has_flag(int argc, char** argv, const char* flag) {
  for (int i = 1; i < argc; ++i)
    if (std::strcmp(argv[i], flag) == 0) return true;
  return false;
}

constexpr char kUsage[] =
    "usage: gslam_ros [--print-config] [rgb/image:=TOPIC depth/image:=TOPIC rgb/camera_info:=TOPIC] "
    "[_name:=value ...]\n"
    "gslam live as a ROS 1 node: subscribes rgb/image, depth/image, rgb/camera_info; publishes /tf, "
    "~odometry, ~path, ~map_cloud, ~render; services ~save, ~reset. Parameters: README, \"On a robot\".\n";

}  // namespace

int run_ros_node(int argc, char** argv) {
  if (has_flag(argc, argv, "--help") || has_flag(argc, argv, "-h")) {
    std::fputs(kUsage, stdout);
    return 0;
  }
  if (has_flag(argc, argv, "--print-config")) {
    const NodeSetup setup = setup_from(ros1::command_line_parameters(argc, argv));
    std::printf("%s\n", slam_config_to_json(setup.config).dump(2).c_str());
    return 0;
  }
  ros1::Connection connection(argc, argv, "gslam");
  const NodeSetup setup = setup_from(connection.parameters());
  const RosNodeOptions& o = setup.options;
  LiveOptions live;
  live.out = o.out;
  live.overwrite = o.overwrite;
  live.headless = true;
  live.catch_up = o.catch_up;
  live.checkpoint_seconds = o.checkpoint_seconds;
  live.backend.backend = o.backend;
  live.backend.threads = o.threads;
  RosHost host(connection, o);
  // Before the host goes (and however the run ends): no service call waits on it any more, and
  // no callback runs.
  struct StopFirst {
    RosHost& host;
    ros1::Connection& connection;
    ~StopFirst() {
      host.close();
      connection.stop();
    }
  } stop_first{host, connection};
  return run_live(live, setup.config, &host);
}

}  // namespace app
