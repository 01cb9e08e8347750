// `gslam live`: the picture it composes, headless replay with dropped frames, a watched folder,
// Ctrl-C, and the real window under Xvfb.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "app/run_gslam.h"
#include "datasets/synthetic_sequence.h"
#include "io/image_io.h"
#include "io/trajectory.h"
#include "splat/vulkan_rasterizer.h"
#include "support/image_counts.h"
#include "support/json_file.h"
#include "support/random_scene.h"
#include "support/temp_dir.h"
#include "viewer/live_view.h"

namespace {

using gslam::test::TempDir;

// The map panel's pixels of a colour, and its splats.
int count_colour_in_panel(const splat::Image8& image, const uint8_t rgb[3]) {
  return gslam::test::count_colour(image, rgb, app::kMapPanelWidth);
}
int count_map_pixels_in_panel(const splat::Image8& image) { return gslam::test::count_map_pixels(image, app::kMapPanelWidth); }

std::filesystem::path synthetic(const TempDir& dir, int frames) {
  app::SyntheticOptions o;
  o.frames = frames;
  app::write_synthetic_sequence(dir / "seq", o);
  return dir / "seq";
}

using gslam::test::read_json;

TEST(LiveView, ComposesMapTrajectoryCameraAndInput) {
  gslam::test::SceneOptions o;
  o.count = 300;
  o.max_opacity = 0.95;
  const auto scene = gslam::test::make_random_scene<float>(o);
  app::LiveViewState state;
  state.map = std::make_shared<const splat::Gaussians>(scene.gaussians);
  // The scene's camera, and a short path behind it.
  state.T_world_cam = scene.camera.T_cam_world.inverse();
  for (int i = 0; i < 5; ++i) {
    state.trajectory.push_back(state.T_world_cam * Eigen::Vector3d(0.05 * i - 0.2, 0, 0.02 * i));
  }
  state.input = splat::Image8(64, 48, 3, 200);
  auto rasterizer = splat::make_cpu_rasterizer({1});
  const splat::Image8 picture = app::compose_live_view(state, {}, *rasterizer);
  ASSERT_EQ(picture.width, app::kLiveViewWidth);
  ASSERT_EQ(picture.height, app::kLiveViewHeight);
  EXPECT_GT(count_map_pixels_in_panel(picture), 5000) << "the map should fill part of the panel";
  EXPECT_GT(count_colour_in_panel(picture, app::kTrajectoryRgb), 20) << "trajectory not drawn";
  EXPECT_GT(count_colour_in_panel(picture, app::kCameraRgb), 20) << "current camera not drawn";
  EXPECT_EQ(picture.at(app::kMapPanelWidth + 10, 10, 0), 200) << "input frame not shown";
  app::ViewCamera orbit;
  orbit.follow = false;
  EXPECT_GT(count_map_pixels_in_panel(app::compose_live_view(state, orbit, *rasterizer)), 1000)
      << "orbit view";
}

TEST(CliLive, HeadlessReplayWritesReconstructOutputsAndCountsDroppedFrames) {
  TempDir dir;
  const auto seq = synthetic(dir, 40);
  // 40 frames replayed at 50x their 30 Hz (1,500 frames/s): faster than any CPU tracks, so
  // some are dropped.
  const auto r =
      run_gslam("live " + seq.string() + " --out " + (dir / "run").string() + " --headless --speed 50");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* name :
       {"trajectory.txt", "map.ply", "map.glb", "summary.json", "keyframes/kf_0000.png"}) {
    EXPECT_TRUE(std::filesystem::exists(dir / "run" / name)) << name;
  }
  const nlohmann::json s = read_json(dir / "run" / "summary.json");
  const auto& live = s.at("live");
  const std::size_t frames = s.at("frames").get<std::size_t>();
  EXPECT_TRUE(s.at("complete").get<bool>());
  EXPECT_EQ(live.at("frames_received").get<std::size_t>(), 40u);
  EXPECT_EQ(frames + live.at("frames_dropped").get<std::size_t>(), 40u)
      << "every frame is tracked or dropped";
  EXPECT_GT(live.at("frames_dropped").get<std::size_t>(), 0u)
      << "replay faster than tracking must drop";
  EXPECT_GE(frames, 2u);
  EXPECT_GT(live.at("tracking_latency_ms").at("p95").get<double>(), 0);
  EXPECT_EQ(app::read_tum_trajectory(dir / "run" / "trajectory.txt").size(), frames);
  // The console and summary.json give the same count (the replay stops when the run does).
  const std::string said = "dropped " + std::to_string(live.at("frames_dropped").get<std::size_t>()) + ",";
  EXPECT_NE(r.output.find("live: tracked " + std::to_string(frames) + " frames, " + said), std::string::npos)
      << said << " in " << r.output;
}

TEST(CliLive, WatchedFolderTakesPairsAsTheyAppearUntilEnd) {
  TempDir dir;
  const auto seq = synthetic(dir, 3);
  const auto watched = dir / "camera";
  std::filesystem::create_directories(watched / "rgb");
  std::filesystem::create_directories(watched / "depth");
  std::filesystem::copy_file(seq / "intrinsics.txt", watched / "intrinsics.txt");
  // A driver's output: pairs named by timestamp, then END.
  int k = 0;
  for (const auto& entry : std::filesystem::directory_iterator(seq / "rgb")) {
    const std::string name = "1000." + std::to_string(k++) + ".png";
    std::filesystem::copy_file(entry.path(), watched / "rgb" / name);
    std::filesystem::copy_file(seq / "depth" / entry.path().filename(), watched / "depth" / name);
  }
  std::ofstream(watched / "END") << "\n";
  const auto r = run_gslam("live " + watched.string() + " --watch --out " + (dir / "run").string() +
                           " --headless");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json s = read_json(dir / "run" / "summary.json");
  EXPECT_GE(s.at("frames").get<std::size_t>(), 1u);
  EXPECT_EQ(
      s.at("frames").get<std::size_t>() + s.at("live").at("frames_dropped").get<std::size_t>(), 3u);
  const auto missing = run_gslam("live " + (dir / "nowhere").string() + " --watch --out " +
                                 (dir / "x").string() + " --headless");
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.output.find("watched folder does not exist"), std::string::npos)
      << missing.output;
}

// A watched camera whose intrinsics.txt states its lens: frames are undistorted, and the run
// records the raw camera beside the pinhole one, so that eval reads the frames alike.
TEST(CliLive, WatchedCameraWithALensIsUndistortedAndRecorded) {
  TempDir dir;
  app::SyntheticOptions o;
  o.frames = 3;
  o.distortion = {0.262383, -0.953104, -0.005358, 0.002628, 1.163314};
  app::write_synthetic_sequence(dir / "camera", o);  // the generator's names are timestamps
  std::filesystem::remove(dir / "camera" / "rgb.txt");
  std::filesystem::remove(dir / "camera" / "depth.txt");
  std::ofstream(dir / "camera" / "END") << "\n";
  const auto r = run_gslam("live " + (dir / "camera").string() + " --watch --every-frame --out " +
                           (dir / "run").string() + " --headless");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json input = read_json(dir / "run" / "summary.json").at("input");
  ASSERT_TRUE(input.contains("lens")) << input.dump();
  EXPECT_DOUBLE_EQ(input.at("lens").at("k3").get<double>(), 1.163314);
  EXPECT_DOUBLE_EQ(input.at("lens").at("fx").get<double>(), 260);
  EXPECT_GT(input.at("intrinsics").at("fx").get<double>(), 260)
      << "the pinhole camera the frames were tracked in";
}

TEST(CliLive, CtrlCWritesCompleteOutputs) {
  TempDir dir;
  const auto seq = synthetic(dir, 30);
  // Replayed at a tenth of its rate (3 frames/s), the run is interrupted once it reports its
  // first frame, with 29 still to come from the replay clock.
  const auto r = gslam::test::run_and_interrupt(std::string(GSLAM_BINARY) + " live " + seq.string() + " --out " +
                                                    (dir / "run").string() + " --headless" + gslam::test::replay_speed(0.1),
                                                "live 1,");
  ASSERT_TRUE(r.event_seen) << r.output;
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("interrupted: writing what was done"), std::string::npos) << r.output;
  const nlohmann::json s = read_json(dir / "run" / "summary.json");
  EXPECT_TRUE(s.at("complete").get<bool>());
  EXPECT_TRUE(s.at("live").at("interrupted").get<bool>());
  EXPECT_LT(s.at("frames").get<std::size_t>(), 30u);
  EXPECT_TRUE(std::filesystem::exists(dir / "run" / "map.ply"));
}

// The real window, drawn by Mesa's software OpenGL under Xvfb, with tracking and mapping on
// the Vulkan backend (lavapipe in CI) where the build has it: its screenshot shows the map,
// the yellow trajectory, the red current camera and the input frame.
TEST(CliLive, WindowUnderXvfbShowsMapAndTrajectory) {
  if (!gslam::test::program_available("xvfb-run"))
    GTEST_SKIP() << "xvfb-run not found (apt-get install xvfb xauth)";
  TempDir dir;
  const auto seq = synthetic(dir, 12);
  const auto shot = dir / "shot.png";
  // Every frame is replayed once the previous one is tracked (no clock: what the screenshot
  // shows does not depend on the machine's speed); lavapipe maps with a lighter load.
  std::ofstream(dir / "light.json") << R"({"mapping": {"iterations": 10}})";
  const std::string backend =
      std::string(" --every-frame") +
      (splat::vulkan_backend_built() ? " --backend vulkan --config " + (dir / "light.json").string() : "");
  // Under AddressSanitizer, leak checking is off for this process only: Mesa's GLX driver,
  // unloaded by glfwTerminate, leaves 112 bytes that LeakSanitizer can no longer attribute
  // (seen in `scripts/test.sh --sanitize`); memory errors are still checked.
  const auto r = gslam::test::run_command(
      "ASAN_OPTIONS=detect_leaks=0 xvfb-run -a -s '-screen 0 1280x1024x24' " +
      std::string(GSLAM_BINARY) + " live " +
      seq.string() + " --out " + (dir / "run").string() + backend + " --screenshot " +
      shot.string() + " --screenshot-after 3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_TRUE(std::filesystem::exists(shot)) << r.output;
  const splat::Image8 picture = app::read_png_rgb8(shot);
  ASSERT_EQ(picture.width, app::kLiveViewWidth);
  EXPECT_GT(count_map_pixels_in_panel(picture), 20000) << "map not drawn";
  EXPECT_GT(count_colour_in_panel(picture, app::kTrajectoryRgb), 20) << "trajectory not drawn";
  EXPECT_GT(count_colour_in_panel(picture, app::kCameraRgb), 20) << "camera not drawn";
  ASSERT_TRUE(std::filesystem::exists(dir / "run" / "summary.json"));
  // The run's bus traffic: the maps uploaded and the gradients read back on Vulkan, none on the CPU.
  // Mapping on the device where there is one (the resident map), else on the host.
  const nlohmann::json summary = read_json(dir / "run" / "summary.json");
  const auto transfers = summary.at("transfers_mib");
  for (const char* way : {"to_device", "to_host"}) {
    if (splat::vulkan_backend_built()) EXPECT_GT(transfers.at(way).get<double>(), 0) << way;
    else EXPECT_EQ(transfers.at(way).get<double>(), 0) << way;
  }
  EXPECT_EQ(summary.at("mapping").at("on_device").get<bool>(), splat::vulkan_backend_built());
}

}  // namespace

namespace {

// `live` and `reconstruct` are one SLAM system: on the same frames, taken at a rate where none
// is dropped, they give the same trajectory. (The odometry does not depend on the map, so this
// holds whatever mapping keeps up with; the final sweep, which only reconstruct runs, is off.)
// Exactly so where nothing moves keyframes during the sequence. Covisibility (on by default)
// does, and live's mapping thread hands its corrections to tracking a few frames later than
// reconstruct's: each alignment then starts from another guess and stops at another point
// within its step tolerance (10 um), so the two agree to a fraction of a millimetre.
TEST(CliLive, GivesReconstructsTrajectoryWhenNoFrameIsDropped) {
  TempDir dir;
  const auto seq = synthetic(dir, 16);
  struct Case {
    const char* name;
    const char* config;
    double metres, rotation;
  };
  for (const Case& c : {Case{"no_covisibility", R"({"refine_passes": 0, "loop_closure": {"covisible_keyframes": 0}})", 1e-6, 1e-6},
                        Case{"defaults", R"({"refine_passes": 0})", 5e-4, 5e-4}}) {
    SCOPED_TRACE(c.name);
    const std::filesystem::path run = dir / c.name;
    std::filesystem::create_directories(run);
    std::ofstream(run / "config.json") << c.config;
    const std::string config = " --config " + (run / "config.json").string();
    const auto offline = run_gslam("reconstruct " + seq.string() + " --out " + (run / "offline").string() + config);
    ASSERT_EQ(offline.exit_code, 0) << offline.output;
    const auto live = run_gslam("live " + seq.string() + " --out " + (run / "live").string() + " --headless --every-frame" + config);
    ASSERT_EQ(live.exit_code, 0) << live.output;
    ASSERT_EQ(read_json(run / "live" / "summary.json").at("live").at("frames_dropped").get<int>(), 0)
        << "--every-frame drops none";
    const auto a = app::read_tum_trajectory(run / "offline" / "trajectory.txt");
    const auto b = app::read_tum_trajectory(run / "live" / "trajectory.txt");
    ASSERT_EQ(a.size(), b.size());
    double worst = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      const double moved = (a[i].T_world_cam.translation() - b[i].T_world_cam.translation()).norm();
      worst = std::max(worst, moved);
      EXPECT_LT(moved, c.metres) << "frame " << i;
      EXPECT_LT((a[i].T_world_cam.linear() - b[i].T_world_cam.linear()).cwiseAbs().maxCoeff(), c.rotation) << "frame " << i;
    }
    std::printf("%s: live and reconstruct differ by at most %.4f mm\n", c.name, worst * 1e3);
  }
}

}  // namespace

namespace {

// A live run folder is a run folder: eval scores it against the replayed sequence's ground
// truth and render draws it from its recorded camera, as for reconstruct.
TEST(CliLive, RunFolderTakesEvalAndRender) {
  TempDir dir;
  const auto seq = synthetic(dir, 12);
  std::ofstream(dir / "quick.json") << R"({"mapping": {"iterations": 5}})";
  const auto live = run_gslam("live " + seq.string() + " --out " + (dir / "run").string() + " --headless --every-frame --config " +
                              (dir / "quick.json").string());
  ASSERT_EQ(live.exit_code, 0) << live.output;
  const nlohmann::json input = read_json(dir / "run" / "summary.json").at("input");
  EXPECT_EQ(input.at("intrinsics").at("width").get<int>(), 320);
  const auto eval = run_gslam("eval " + (dir / "run").string());
  ASSERT_EQ(eval.exit_code, 0) << eval.output;
  const nlohmann::json e = read_json(dir / "run" / "eval.json");
  EXPECT_EQ(e.at("ate").at("matched_frames").get<int>(), 12);
  EXPECT_LT(e.at("ate").at("rmse_m").get<double>(), 0.02) << "the synthetic sequence tracks to millimetres";
  const auto render = run_gslam("render " + (dir / "run").string() + " --out " + (dir / "views").string() + " --views 3");
  ASSERT_EQ(render.exit_code, 0) << render.output;
  EXPECT_NE(render.output.find("rendered 3 views"), std::string::npos) << render.output;
  EXPECT_NE(render.output.find("at 320x240"), std::string::npos) << render.output;
}

// Mapping that falls behind skips keyframes while the stream runs; at its end they are mapped
// (catch-up) before the outputs are written, unless --no-catch-up. With 40 mapping steps a
// keyframe (each a render and its gradient) and a keyframe every second frame, mapping a
// keyframe takes tens of times longer than tracking the two frames before the next (75x per
// frame measured on a loaded machine), so keyframes are skipped on any machine, loaded or not.
TEST(CliLive, CatchUpMapsTheKeyframesMappingSkipped) {
  TempDir dir;
  const auto seq = synthetic(dir, 12);
  std::ofstream(dir / "heavy.json") << R"({"keyframe_every": 2, "mapping": {"iterations": 40}})";
  const std::string args = " --headless --every-frame --config " + (dir / "heavy.json").string();
  const auto caught_up = run_gslam("live " + seq.string() + " --out " + (dir / "caught_up").string() + args);
  ASSERT_EQ(caught_up.exit_code, 0) << caught_up.output;
  const nlohmann::json a = read_json(dir / "caught_up" / "summary.json");
  const auto& live = a.at("live");
  EXPECT_GT(live.at("keyframes_caught_up").get<std::size_t>(), 0u) << caught_up.output;
  EXPECT_EQ(live.at("keyframes_skipped").get<std::size_t>(), 0u) << "every skipped keyframe is mapped at the end";
  EXPECT_EQ(live.at("keyframes_mapped").get<std::size_t>(), a.at("keyframes").get<std::size_t>());
  EXPECT_NE(caught_up.output.find("catch-up"), std::string::npos) << "catch-up shows progress: " << caught_up.output;

  const auto skipped = run_gslam("live " + seq.string() + " --out " + (dir / "skipped").string() + args + " --no-catch-up");
  ASSERT_EQ(skipped.exit_code, 0) << skipped.output;
  const nlohmann::json b = read_json(dir / "skipped" / "summary.json");
  EXPECT_EQ(b.at("live").at("keyframes_caught_up").get<std::size_t>(), 0u);
  EXPECT_GT(b.at("live").at("keyframes_skipped").get<std::size_t>(), 0u);
  EXPECT_EQ(b.at("live").at("keyframes_mapped").get<std::size_t>() + b.at("live").at("keyframes_skipped").get<std::size_t>(),
            b.at("keyframes").get<std::size_t>());
}

}  // namespace
