#include "commands/live_command.h"

#include "commands/interrupt.h"
#include "commands/label_maps.h"

#include <algorithm>
#include <atomic>
#include <csignal>
#include <optional>
#include <cstdio>
#include <deque>
#include <mutex>
#include <thread>

#include "io/image_io.h"
#include "slam/slam_system.h"
#include "viewer/live_view.h"
#include "commands/progress.h"
#include "commands/run_input.h"
#include "commands/run_outputs.h"
#include "io/slam_config_io.h"
#include "viewer/viewer_window.h"
#include "splat/error.h"

namespace app {
namespace {

using Clock = std::chrono::steady_clock;


// Latencies of the most recent frames (bounded, so a long session does not grow memory).
class LatencyWindow {
 public:
  void add(double ms) {
    if (values_.size() == kCapacity) values_.pop_front();
    values_.push_back(ms);
  }
  double percentile(double q) const {
    if (values_.empty()) return 0;
    std::vector<double> sorted(values_.begin(), values_.end());
    const std::size_t k = std::min(
        sorted.size() - 1, static_cast<std::size_t>(q * static_cast<double>(sorted.size())));
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(k), sorted.end());
    return sorted[k];
  }

 private:
  static constexpr std::size_t kCapacity = 4096;
  std::deque<double> values_;
};

splat::Image8 to_image8(const splat::RgbdFrame& frame) {
  splat::Image8 image(frame.width(), frame.height(), 3);
  for (std::size_t k = 0; k < image.data.size(); ++k) {
    image.data[k] = static_cast<uint8_t>(std::clamp(frame.rgb[k], 0.f, 1.f) * 255.f + 0.5f);
  }
  return image;
}

// What the pipeline thread shares with the window thread.
struct Shared {
  std::mutex mutex;
  LiveViewState view;
  std::string stats = "gslam live: waiting for frames";
  std::size_t tracked = 0;
  bool paused = false, snapshot = false;
  bool finished = false;  // the stream has ended and mapping has caught up: the map is final
  std::atomic<bool> stop{false};
};

}  // namespace

int run_live(const LiveOptions& o) { return run_live(o, load_slam_config(o.config), nullptr); }

int run_live(const LiveOptions& o, const SlamConfig& config, LiveHost* host) {
  if (!(o.checkpoint_seconds > 0)) throw splat::Error("--checkpoint-seconds must be > 0");
  // The dataset is opened (and checked) first; the replay clock starts once everything else is
  // ready, so start-up time does not count as dropped frames.
  std::optional<Dataset> dataset;
  if (!o.watch && !host) dataset = open_dataset(o.source, o.dataset_options);
  std::string note;
  auto tracking_rasterizer = make_rasterizer(o.backend, note);
  std::fprintf(stderr, "%s\n", note.c_str());
  // Mapping leaves one core to tracking and the camera (a CPU backend with all cores would make
  // tracking wait for its turn).
  BackendChoice mapping_backend = o.backend;
  if (mapping_backend.threads == 0) {
    mapping_backend.threads = std::max(1, static_cast<int>(std::thread::hardware_concurrency()) - 1);
  }
  auto mapping_rasterizer = make_rasterizer(mapping_backend, note);
  std::unique_ptr<ViewerWindow> window;
  if (!o.headless && !host) window = std::make_unique<ViewerWindow>("gslam live");
  auto view_rasterizer = splat::make_cpu_rasterizer({1});
  auto make_system = [&] { return std::make_unique<SlamSystem>(*tracking_rasterizer, *mapping_rasterizer, config); };
  std::unique_ptr<SlamSystem> live = make_system();
  // What the run read, as reconstruct records it, so that eval and render take a live run folder.
  nlohmann::json input;
  if (dataset) input = run_input_json(o.source, *dataset, o.dataset_options.max_frames, 0, config);
  WatchOptions watch_options = o.watch_options;
  watch_options.every_frame = o.speed == kEveryFrame;
  std::unique_ptr<FrameSource> source = host      ? host->open_source()
                                       : o.watch ? make_watch_source(o.source, watch_options)
                                                 : make_replay_source(std::move(*dataset), o.speed);
  std::fprintf(stderr, "live: %s%s\n", source->describe().c_str(), o.headless ? ", headless" : "");
  auto outputs = std::make_unique<RunOutputs>(o.out, source->describe(), *tracking_rasterizer, o.overwrite);
  if (!input.is_null()) outputs->extra()["input"] = input;
  Shared shared;
  LatencyWindow latency;
  std::vector<StampedPose> truth;
  std::size_t paused_dropped = 0;
  const std::size_t max_frames =
      o.dataset_options.max_frames > 0 ? std::size_t(o.dataset_options.max_frames) : 0;
  // SIGINT/SIGTERM: the run stops taking frames (and catching up) and writes its outputs.
  std::optional<InterruptGuard> interrupt(std::in_place);
  const auto dropped = [&] { return source->dropped() + paused_dropped; };

  // Outputs with the poses as mapping has corrected them so far.
  auto checkpoint = [&] {
    const std::shared_ptr<const splat::Gaussians> map = live->map();
    if (!map) return;  // no frame yet
    outputs->update_poses(live->trajectory());
    outputs->set_mapping(live->mapping_totals(), live->loop_events(), live->mapping_on_device(), false);
    outputs->checkpoint(*map, live->keyframes(), true);
  };
  // A host's request between frames: the run folder written now, or the map forgotten.
  auto serve = [&](const LiveRequest& request) {
    if (request.kind == LiveRequest::kSave) {
      if (outputs->records().empty()) return request.answer(false, "nothing to save: no frame tracked yet");
      checkpoint();
      return request.answer(true, "wrote trajectory.txt, map.ply and summary.json in " + o.out.string());
    }
    live.reset();  // its mapping thread stops before the next one starts
    live = make_system();
    outputs = std::make_unique<RunOutputs>(o.out, source->describe(), *tracking_rasterizer, true);
    truth.clear();
    {
      std::lock_guard lock(shared.mutex);
      shared.view = LiveViewState();
    }
    request.answer(true, "map and trajectory cleared; the next frame starts a new map");
  };
  // Between frames the viewer and the host are given the map that mapping has made since.
  auto show_latest_map = [&] {
    std::shared_ptr<const splat::Gaussians> map = live->map();
    {
      std::lock_guard lock(shared.mutex);
      if (map == shared.view.map) return;
      shared.view.map = map;
    }
    if (host) host->map_changed(std::move(map));
  };
  auto pipeline = [&] {
    Progress progress("live", 0, "frames");
    Clock::time_point last_checkpoint = Clock::now();
    while (!shared.stop && !InterruptGuard::interrupted()) {
      if (host) {
        while (std::optional<LiveRequest> request = host->next_request()) serve(*request);
      }
      std::optional<ArrivedFrame> arrived = source->next(std::chrono::milliseconds(100));
      if (!arrived) {
        if (source->finished()) break;
        show_latest_map();
        continue;
      }
      bool paused = false, snapshot = false;
      {
        std::lock_guard lock(shared.mutex);
        paused = shared.paused;
        snapshot = std::exchange(shared.snapshot, false);
      }
      if (snapshot) checkpoint();
      if (paused) {  // the camera goes on; what arrives while paused is dropped
        ++paused_dropped;
        continue;
      }
      const splat::Camera camera = arrived->frame.camera;
      std::optional<splat::Image8> shown;
      if (window) shown = to_image8(arrived->frame);
      const FrameRecord record = live->process(std::move(arrived->frame));
      const double ms =
          std::chrono::duration<double, std::milli>(Clock::now() - arrived->arrived).count();
      latency.add(ms);
      if (!record.tracked)
        std::fprintf(stderr, "\nframe at %.3f s: tracking failed (%s)\n", record.timestamp,
                     record.reason.c_str());
      outputs->add(record, 0);
      if (host) host->tracked(camera, record, *live);
      if (arrived->T_world_cam_truth)
        truth.push_back({record.timestamp, *arrived->T_world_cam_truth});
      const std::size_t n = outputs->records().size();
      char stats[256];
      std::snprintf(stats, sizeof(stats),
                    "gslam live: %zu frames, %.1f frames/s, latency p95 %.0f ms, %zu Gaussians, "
                    "%zu dropped%s",
                    n, static_cast<double>(n) / std::max(1e-9, outputs->elapsed_seconds()),
                    latency.percentile(0.95), record.gaussians, dropped(),
                    window && shared.paused ? ", paused" : "");
      {
        std::lock_guard lock(shared.mutex);
        shared.view.map = live->map();
        shared.view.trajectory.push_back(record.T_world_cam.translation());
        shared.view.T_world_cam = record.T_world_cam;
        if (shown) shared.view.input = std::move(*shown);
        shared.stats = stats;
        shared.tracked = n;
      }
      progress.update(n, std::to_string(record.gaussians) + " Gaussians, latency p95 " +
                             std::to_string(static_cast<int>(latency.percentile(0.95))) + " ms, " +
                             std::to_string(dropped()) + " dropped");
      if (std::chrono::duration<double>(Clock::now() - last_checkpoint).count() >=
          o.checkpoint_seconds) {
        checkpoint();
        last_checkpoint = Clock::now();
      }
      if (max_frames > 0 && n >= max_frames) break;
    }
    progress.finish();
  };
  // After the stream: the source stops (its counts are final), mapping finishes and maps the
  // keyframes it skipped, and the window is given the final map.
  auto finish_mapping = [&] {
    source->stop();
    if (InterruptGuard::interrupted()) {
      std::fprintf(stderr, "interrupted: writing what was done (no keyframe renders; gslam render RUN draws views)\n");
    }
    const std::size_t backlog = live->mapping_backlog();
    if (backlog > 0 && o.catch_up && !InterruptGuard::interrupted()) {
      Progress progress("catch-up", backlog, "skipped keyframes mapped");
      live->catch_up_mapping(
          [&](std::size_t done, std::size_t total) {
            progress.update(done);
            std::lock_guard lock(shared.mutex);
            shared.view.map = live->map();
            shared.stats = "gslam live: mapping skipped keyframes, " + std::to_string(done) + " of " + std::to_string(total);
          },
          [] { return InterruptGuard::interrupted(); });
      progress.finish();
    }
    live->finish();
    std::lock_guard lock(shared.mutex);
    shared.view.map = live->map();
    shared.finished = true;
  };

  std::exception_ptr error;
  if (!window) {
    pipeline();
    finish_mapping();
  } else {
    std::thread worker([&] {
      try {
        pipeline();
        finish_mapping();
      } catch (...) {
        error = std::current_exception();
        std::lock_guard lock(shared.mutex);
        shared.finished = true;
      }
    });
    bool screenshot_taken = false;
    std::size_t snapshots = 0;
    while (true) {
      window->poll();
      LiveViewState state;
      std::string title;
      std::size_t tracked = 0;
      bool finished = false;
      {
        std::lock_guard lock(shared.mutex);
        shared.paused = window->paused();
        state = shared.view;
        title = shared.stats;
        tracked = shared.tracked;
        finished = shared.finished;
      }
      if (window->closed() || InterruptGuard::interrupted()) shared.stop = true;
      if (window->closed()) break;  // the worker still finishes mapping and the outputs follow
      // The screenshot once enough frames are tracked and mapping has drawn a map, or of the
      // final map if the stream ended first.
      const bool has_map = state.map && !state.map->empty();
      const bool want_screenshot =
          !o.screenshot.empty() && !screenshot_taken &&
          ((tracked >= static_cast<std::size_t>(std::max(1, o.screenshot_after)) && has_map) || finished);
      const bool want_snapshot = window->take_snapshot_request();
      splat::Image8 capture;
      window->show(compose_live_view(state, window->view(), *view_rasterizer), title,
                   want_screenshot || want_snapshot ? &capture : nullptr);
      if (want_screenshot) {
        write_png_rgb8(o.screenshot, capture);
        screenshot_taken = true;
      }
      if (want_snapshot) {
        char name[48];
        std::snprintf(name, sizeof(name), "snapshot_%03zu.png", snapshots++);
        std::filesystem::create_directories(o.out / "snapshots");
        write_png_rgb8(o.out / "snapshots" / name, capture);
        std::lock_guard lock(shared.mutex);
        shared.snapshot = true;  // the pipeline writes map.ply, trajectory and summary
      }
      if (finished) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(30));
    }
    worker.join();
  }
  const bool interrupted = InterruptGuard::interrupted();
  interrupt.reset();
  if (error) std::rethrow_exception(error);

  const MappingTotals mapping = live->mapping_totals();
  outputs->update_poses(live->trajectory());
  outputs->set_mapping(mapping, live->loop_events(), live->mapping_on_device(), false);
  if (host) {  // a host's camera, or a watched folder's, is known once frames came
    outputs->extra()["input"] = host->input_json(source->intrinsics(), config);
  } else if (input.is_null()) {
    outputs->extra()["input"] = run_input_json(o.source, "watched", source->intrinsics(), o.watch_options.depth_scale,
                                               o.dataset_options.max_frames, 0, config);
    if (source->undistortion())
      outputs->extra()["input"]["lens"] = lens_json(*source->undistortion());
    const ColorCameraChoice color = parse_color_camera(o.watch_options.color_camera);
    outputs->extra()["input"]["color_camera"] = color.kind == ColorCameraChoice::kGiven ? color.given.text() : kRegisteredColor;
  }
  outputs->extra()["live"] = {{"source", source->describe()},
                             {"frames_received", source->delivered() + source->dropped()},
                             {"frames_dropped", dropped()},
                             {"frames_dropped_while_paused", paused_dropped},
                             {"tracking_latency_ms", {{"p50", latency.percentile(0.5)}, {"p95", latency.percentile(0.95)}}},
                             {"keyframes_mapped", mapping.keyframes_mapped},
                             {"keyframes_caught_up", mapping.keyframes_caught_up},
                             {"keyframes_skipped", mapping.keyframes_skipped},
                             {"interrupted", interrupted}};
  outputs->set_stopping(interrupted);
  const std::shared_ptr<const splat::Gaussians> map = live->map();
  if (!o.watch && !host && !interrupted && map) {  // the map's classes, from the recording's label images if it has them
    fuse_run_labels(open_dataset(o.source, o.dataset_options), live->trajectory(), *map, *mapping_rasterizer,
                    config.mapping.refine_resolution_factor, *outputs);
  }
  const splat::Gaussians empty;
  outputs->finish(map ? *map : empty, live->keyframes(), *tracking_rasterizer, source->intrinsics(), truth);
  std::printf(
      "live: tracked %zu frames, dropped %zu, latency p95 %.0f ms, %zu keyframes mapped (%zu caught up at the end, "
      "%zu skipped), %zu Gaussians -> %s\n",
      outputs->records().size(), dropped(), latency.percentile(0.95), mapping.keyframes_mapped,
      mapping.keyframes_caught_up, mapping.keyframes_skipped, map ? map->size() : std::size_t(0), o.out.c_str());
  return 0;
}

}  // namespace app
