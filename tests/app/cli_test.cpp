// The gslam executable end to end: outputs on good input, one-line errors and non-zero exits
// on bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "app/run_gslam.h"
#include "datasets/synthetic_sequence.h"
#include "io/image_io.h"
#include "io/ply_io.h"
#include "io/run_folder.h"
#include "io/trajectory.h"
#include "slam/slam_config.h"
#include "support/golden_case.h"
#include "support/random_scene.h"
#include "support/temp_dir.h"
#include "support/test_data.h"

namespace {

using gslam::test::RunResult;
using gslam::test::TempDir;

splat::Gaussians small_map() {
  gslam::test::SceneOptions o;
  o.count = 200;
  o.sh_degree = 1;
  return gslam::test::make_random_scene<float>(o).gaussians;
}

// DIR/seq, a 6-frame synthetic sequence, and DIR/quick.json, a configuration that reconstructs
// it in about a second.
void write_quick_run_inputs(const TempDir& dir) {
  app::SyntheticOptions o;
  o.frames = 6;
  app::write_synthetic_sequence(dir / "seq", o);
  gslam::test::write_text(dir / "quick.json", R"({"refine_passes": 1, "mapping": {"iterations": 3}})");
}

TEST(CliRender, OrbitWritesPngAndExrAndSummary) {
  TempDir dir;
  app::write_ply(dir / "map.ply", small_map());
  const RunResult r = run_gslam("render " + (dir / "map.ply").string() + " --out " + (dir / "out").string() +
                                " --orbit 3 --size 80x60 --format png,exr --backend cpu");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("rendered 3 views of 200 Gaussians at 80x60"), std::string::npos) << r.output;
  for (int i = 0; i < 3; ++i) {
    const std::string stem = (dir / "out" / ("view_000" + std::to_string(i))).string();
    const splat::Image8 png = app::read_png_rgb8(stem + ".png");
    EXPECT_EQ(png.width, 80);
    const app::ExrImage exr = app::read_exr(stem + ".exr");
    float covered = 0;
    for (float a : exr.channels.at("A")) covered += a;
    EXPECT_GT(covered, 10.f) << "view " << i << " should show the map";
  }
}

TEST(CliRender, TrajectoryWithIntrinsicsRendersOneViewPerPose) {
  TempDir dir;
  app::write_ply(dir / "map.ply", small_map());
  gslam::test::write_text(dir / "traj.txt", "# t tx ty tz qx qy qz qw\n0.0 0 0 0 0 0 0 1\n0.1 0.05 0 0 0 0 0 1\n");
  const RunResult r = run_gslam("render " + (dir / "map.ply").string() + " --out " + (dir / "out").string() +
                                " --trajectory " + (dir / "traj.txt").string() + " --intrinsics 60,60,32,24,64,48");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "view_0001.png"));
}

// gsplat's golden render through the command line: the map as a PLY, its camera as a one-pose
// TUM trajectory with --intrinsics. A named trajectory is rendered at its poses: every pixel
// matches gsplat within the golden tolerance plus the PNG's 8-bit rounding.
TEST(CliRender, TrajectoryRendersGsplatsGoldenViewAtItsPose) {
  GSLAM_REQUIRE_SHARED_DATA(path, "gsplat_reference_render_brush/basic_case.safetensors");
  const gslam::test::GoldenCase golden = gslam::test::load_golden_case(path);
  TempDir dir;
  app::write_ply(dir / "map.ply", golden.gaussians);
  app::write_tum_trajectory(dir / "camera.txt", {{0.0, golden.camera.T_cam_world.inverse()}});
  const splat::Camera& k = golden.camera;
  char intrinsics[200];
  std::snprintf(intrinsics, sizeof intrinsics, "%.17g,%.17g,%.17g,%.17g,%d,%d", k.fx, k.fy, k.cx, k.cy, k.width, k.height);
  const RunResult r = run_gslam("render " + (dir / "map.ply").string() + " --out " + (dir / "out").string() + " --trajectory " +
                                (dir / "camera.txt").string() + " --intrinsics " + intrinsics + " --backend cpu");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("path: recorded, at the 1 poses of"), std::string::npos) << "the output says which path: " << r.output;
  const splat::Image8 png = app::read_png_rgb8(dir / "out" / "view_0000.png");
  ASSERT_EQ(png.width, k.width);
  ASSERT_EQ(png.height, k.height);
  const auto& ref = golden.tensor("out_img").values;  // [H, W, 4]
  float worst = 0;
  for (int y = 0; y < k.height; ++y) {
    for (int x = 0; x < k.width; ++x) {
      for (int c = 0; c < 3; ++c) {
        const float expected = std::clamp(ref[(static_cast<std::size_t>(y) * k.width + x) * 4 + c], 0.f, 1.f);
        const float got = png.at(x, y, c) / 255.f;
        const float tolerance = 0.5f / 255 + gslam::test::kGoldenAtol + gslam::test::kGoldenRtol * expected;
        worst = std::max(worst, std::abs(got - expected));
        EXPECT_NEAR(got, expected, tolerance) << "pixel " << x << "," << y << " channel " << c;
      }
    }
  }
  std::printf("golden view through the CLI: worst difference %.2f/255\n", 255 * worst);
  // --path novel is what moves the views off the trajectory.
  const RunResult novel = run_gslam("render " + (dir / "map.ply").string() + " --out " + (dir / "novel").string() +
                                    " --trajectory " + (dir / "camera.txt").string() + " --intrinsics " + intrinsics +
                                    " --path novel --backend cpu");
  ASSERT_EQ(novel.exit_code, 0) << novel.output;
  EXPECT_NE(novel.output.find("path: novel"), std::string::npos) << novel.output;
  EXPECT_NE(app::read_png_rgb8(dir / "novel" / "view_0000.png").data, png.data) << "a novel view is another view";
}

// A render folder holds one render: views of an earlier one are refused, and replaced with
// --overwrite (which leaves other files alone).
TEST(CliRender, RefusesAFolderWithAnEarlierRenderUnlessOverwrite) {
  TempDir dir;
  app::write_ply(dir / "map.ply", small_map());
  const std::string render = "render " + (dir / "map.ply").string() + " --out " + (dir / "out").string() + " --size 40x30 --backend cpu";
  ASSERT_EQ(run_gslam(render + " --orbit 6").exit_code, 0);
  gslam::test::write_text(dir / "out" / "notes.txt", "mine\n");
  const RunResult again = run_gslam(render + " --orbit 2");
  EXPECT_NE(again.exit_code, 0);
  EXPECT_NE(again.output.find("holds 6 files of an earlier render"), std::string::npos) << again.output;
  EXPECT_NE(again.output.find("--overwrite"), std::string::npos) << again.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "view_0005.png")) << "a refused render changes nothing";
  const RunResult replaced = run_gslam(render + " --orbit 2 --overwrite");
  ASSERT_EQ(replaced.exit_code, 0) << replaced.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "view_0001.png"));
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "view_0002.png")) << "no stale view is left beside the new ones";
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "notes.txt")) << "only render outputs are removed";
}

// gslam --version: the release, the commit it was built from and the backends built in.
TEST(Cli, VersionNamesReleaseCommitAndBackends) {
  const RunResult r = run_gslam("--version");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.rfind("gslam 0.", 0), 0u) << r.output;
  EXPECT_NE(r.output.find("(commit "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("backends: cpu"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("viewer: "), std::string::npos) << r.output;
}

// The CLI's own mistakes: one line that names the mistake and the nearest valid name.
TEST(Cli, SuggestsTheNearestCommandAndOption) {
  const RunResult command = run_gslam("reconstuct --out x");
  EXPECT_NE(command.exit_code, 0);
  EXPECT_EQ(command.output, "error: unknown command 'reconstuct'; did you mean 'reconstruct'? (gslam --help lists them)\n");
  const RunResult option = run_gslam("live somewhere --out x --max-frame 10");
  EXPECT_NE(option.exit_code, 0);
  EXPECT_EQ(option.output,
            "error: gslam live: unknown option '--max-frame'; did you mean '--max-frames'? (gslam live --help lists them)\n");
  const RunResult far = run_gslam("render m.ply --out x --zzzzzz");
  EXPECT_NE(far.exit_code, 0);
  EXPECT_EQ(far.output, "error: gslam render: unknown option '--zzzzzz' (gslam render --help lists them)\n");
  const RunResult none = run_gslam("");
  EXPECT_NE(none.exit_code, 0);
  EXPECT_NE(none.output.find("error: give a command: render, reconstruct"), std::string::npos) << none.output;
  const RunResult missing = run_gslam("render --out x");
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_EQ(missing.output, "error: gslam render: map is required\n");
}

// A video of an orbit of the bundled demo map (a donut): H.264 with one frame per view, as
// ffprobe (FFmpeg's own reader) decodes it; an odd size or no ffmpeg program is an error.
TEST(CliRender, Mp4OfTheDonutOrbitDecodesWithEveryView) {
  if (!gslam::test::program_available("ffprobe")) GTEST_SKIP() << "ffprobe not found (apt-get install ffmpeg)";
  TempDir dir;
  const RunResult r = run_gslam("render " + std::string(GSLAM_SOURCE_DIR) + "/assets/demo_map.ply --out " + (dir / "out").string() +
                                " --orbit 12 --size 160x120 --format mp4 --backend cpu");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "view_0000.png")) << "mp4 alone writes no frames";
  const RunResult probe = gslam::test::run_command(
      "ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=codec_name,width,height,nb_read_frames -of csv=p=0 " +
      (dir / "out" / "render.mp4").string());
  ASSERT_EQ(probe.exit_code, 0) << probe.output;
  EXPECT_NE(probe.output.find("h264,160,120,12"), std::string::npos) << probe.output;
  const RunResult odd = run_gslam("render " + std::string(GSLAM_SOURCE_DIR) + "/assets/demo_map.ply --out " + (dir / "odd").string() +
                                  " --orbit 2 --size 161x120 --format mp4");
  EXPECT_NE(odd.exit_code, 0);
  EXPECT_NE(odd.output.find("even width and height"), std::string::npos) << odd.output;
  // Without the ffmpeg program: one line naming the file and what to install, and no video.
  const RunResult bare = gslam::test::run_command(
      "PATH=/nonexistent " + std::string(GSLAM_BINARY) + " render " + GSLAM_SOURCE_DIR +
      "/assets/demo_map.ply --out " + (dir / "bare").string() +
      " --orbit 2 --size 160x120 --format mp4 --backend cpu");
  EXPECT_NE(bare.exit_code, 0);
  EXPECT_NE(bare.output.find("render.mp4"), std::string::npos) << bare.output;
  EXPECT_NE(bare.output.find("needs the ffmpeg program"), std::string::npos) << bare.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "bare" / "render.mp4"));
}

TEST(CliRender, RunFolderRendersAlongItsCameras) {
  TempDir dir;
  write_quick_run_inputs(dir);
  ASSERT_EQ(run_gslam("reconstruct " + (dir / "seq").string() + " --out " + (dir / "run").string() + " --config " +
                      (dir / "quick.json").string()).exit_code, 0);
  const RunResult path = run_gslam("render " + (dir / "run").string() + " --out " + (dir / "path").string() + " --views 5");
  ASSERT_EQ(path.exit_code, 0) << path.output;
  EXPECT_NE(path.output.find("rendered 5 views"), std::string::npos) << path.output;
  EXPECT_NE(path.output.find("at 320x240"), std::string::npos) << "the run's own camera: " << path.output;
  const RunResult orbit = run_gslam("render " + (dir / "run").string() + " --out " + (dir / "orbit").string() + " --orbit 3");
  ASSERT_EQ(orbit.exit_code, 0) << orbit.output;
  const splat::Image8 view = app::read_png_rgb8(dir / "orbit" / "view_0000.png");
  int lit = 0;
  for (unsigned char v : view.data) lit += v > 10;
  EXPECT_GT(lit, static_cast<int>(view.data.size() / 4)) << "the orbit looks at the scene";
}

struct BadCase {
  const char* name;
  std::string args;       // {dir} is replaced by the temp dir
  std::string expected;   // fragment of the one-line error
};

class CliBadInput : public ::testing::TestWithParam<BadCase> {};

TEST_P(CliBadInput, PrintsOneLineErrorAndExitsNonZero) {
  TempDir dir;
  app::write_ply(dir / "map.ply", small_map());
  splat::Gaussians empty;
  app::write_ply(dir / "empty.ply", empty);
  gslam::test::write_text(dir / "bad.txt", "0.0 0 0 0 0 0 0\n");
  auto expand = [&](std::string text) {
    for (std::size_t at; (at = text.find("{dir}")) != std::string::npos;) text.replace(at, 5, dir.path().string());
    return text;
  };
  const RunResult r = run_gslam(expand(GetParam().args));
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(expand(GetParam().expected)), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("terminate"), std::string::npos) << "crashed: " << r.output;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, CliBadInput,
    ::testing::Values(
        BadCase{"MissingMap", "render {dir}/none.ply --out {dir}/o", "error: {dir}/none.ply: cannot open file"},
        BadCase{"EmptyMap", "render {dir}/empty.ply --out {dir}/o", "the map has no Gaussians"},
        BadCase{"UnknownFormat", "render {dir}/map.obj --out {dir}/o", "unknown map format '.obj'"},
        BadCase{"ZeroSize", "render {dir}/map.ply --out {dir}/o --size 0x480", "error: size '0x480'"},
        BadCase{"HugeSize", "render {dir}/map.ply --out {dir}/o --size 100000x100000", "error: size"},
        BadCase{"BadTrajectory", "render {dir}/map.ply --out {dir}/o --trajectory {dir}/bad.txt --intrinsics 1,1,1,1,8,8",
                "bad.txt: line 1 has 7 values"},
        BadCase{"TrajectoryWithoutIntrinsics", "render {dir}/map.ply --out {dir}/o --trajectory {dir}/bad.txt",
                "--intrinsics"},
        BadCase{"BadFormat", "render {dir}/map.ply --out {dir}/o --format jpg", "format 'jpg'"},
        BadCase{"UnknownBackend", "render {dir}/map.ply --out {dir}/o --backend metal", "--backend"},
        BadCase{"VulkanDeviceOutOfRange", "render {dir}/map.ply --out {dir}/o --backend vulkan --device 99",
                "error: vulkan:"}),
    [](const auto& info) { return std::string(info.param.name); });

}  // namespace

namespace {

TEST(CliReconstruct, SyntheticDefaultWritesEveryOutputAndEvalReadsThem) {
  TempDir dir;
  const RunResult r = run_gslam("reconstruct --out " + (dir / "run").string() + " --max-frames 12");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* name : {"trajectory.txt", "map.ply", "map.glb", "summary.json", "keyframes/kf_0000.png",
                           "keyframes/kf_0000.exr"}) {
    EXPECT_TRUE(std::filesystem::exists(dir / "run" / name)) << name;
  }
  EXPECT_NE(r.output.find("reconstruct 12/12"), std::string::npos) << "progress should be shown";
  const RunResult e = run_gslam("eval " + (dir / "run").string() + " --dataset " + (dir / "run" / "synthetic_input").string());
  ASSERT_EQ(e.exit_code, 0) << e.output;
  EXPECT_NE(e.output.find("ATE RMSE"), std::string::npos) << e.output;
  for (const char* name : {"eval.json", "trajectory_top.png", "ate_over_time.png", "psnr_over_time.png"}) {
    EXPECT_TRUE(std::filesystem::exists(dir / "run" / name)) << name;
  }
  // One PSNR and SSIM per rendered frame; their mean is the headline figure.
  std::ifstream eval_file(dir / "run" / "eval.json");
  const auto rendering = nlohmann::json::parse(eval_file).at("rendering");
  const auto per_frame_psnr = rendering.at("per_frame").at("psnr_db").get<std::vector<double>>();
  ASSERT_EQ(per_frame_psnr.size(), rendering.at("frames").get<std::size_t>());
  ASSERT_EQ(rendering.at("per_frame").at("ssim").size(), per_frame_psnr.size());
  double mean = 0;
  for (double v : per_frame_psnr) mean += v / double(per_frame_psnr.size());
  EXPECT_NEAR(mean, rendering.at("psnr_db").get<double>(), 1e-9);
  // The refinement's vignetting is in the summary, and eval reports the raw renders too.
  std::ifstream summary_file(dir / "run" / "summary.json");
  nlohmann::json summary = nlohmann::json::parse(summary_file);
  const auto vignetting = summary.at("vignetting");
  EXPECT_TRUE(vignetting.at("k1").is_number() && vignetting.at("k2").is_number()) << vignetting;
  EXPECT_TRUE(rendering.at("psnr_without_vignetting_db").is_number());
  {
    summary["vignetting"] = {{"k1", "strong"}};
    std::ofstream bad(dir / "run" / "summary.json");
    bad << summary.dump();
  }
  const RunResult bad_vignetting = run_gslam("eval " + (dir / "run").string() + " --dataset " + (dir / "run" / "synthetic_input").string());
  EXPECT_NE(bad_vignetting.exit_code, 0);
  EXPECT_NE(bad_vignetting.output.find("summary.json: \"vignetting\" needs numbers k1 and k2"), std::string::npos)
      << bad_vignetting.output;
  const RunResult missing = run_gslam("reconstruct " + (dir / "nowhere").string() + " --out " + (dir / "x").string());
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.output.find("dataset folder does not exist"), std::string::npos) << missing.output;
}

}  // namespace

namespace {

// `--print-config` writes every setting; given back as `--config` it prints the same again, and
// a config with an error stops reconstruct with a one-line message naming the key.
TEST(CliReconstruct, PrintedConfigReadsBackAndBadConfigIsRefusedByName) {
  TempDir dir;
  const RunResult printed = run_gslam("reconstruct --print-config");
  ASSERT_EQ(printed.exit_code, 0) << printed.output;
  const nlohmann::json config = nlohmann::json::parse(printed.output);
  EXPECT_EQ(config.at("refine_passes").get<int>(), app::SlamConfig{}.refine_passes);
  EXPECT_EQ(config.at("refine_coarse_passes").get<int>(), app::SlamConfig{}.refine_coarse_passes);
  EXPECT_EQ(config.at("mapping").at("iterations").get<int>(), 20);
  gslam::test::write_text(dir / "printed.json", printed.output);
  const RunResult again = run_gslam("reconstruct --print-config --config " + (dir / "printed.json").string());
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(nlohmann::json::parse(again.output), config);
  gslam::test::write_text(dir / "bad.json", R"({"mapping": {"window": 3.7}})");
  const RunResult bad = run_gslam("reconstruct --out " + (dir / "run").string() + " --config " + (dir / "bad.json").string());
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("mapping.window: expected an integer"), std::string::npos) << bad.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "run" / "trajectory.txt")) << "nothing runs on a bad config";
}

}  // namespace

namespace {

// Runs that would produce nothing, or ask for more than the machine has, stop with one line.
TEST(CliReconstruct, RefusesInputThatWouldReconstructNothing) {
  TempDir dir;
  const RunResult nan_scale = run_gslam("reconstruct --out " + (dir / "a").string() + " --depth-scale nan");
  EXPECT_NE(nan_scale.exit_code, 0);
  EXPECT_NE(nan_scale.output.find("expected a finite number > 0, got 'nan'"), std::string::npos) << nan_scale.output;
  const RunResult negative = run_gslam("reconstruct --out " + (dir / "a").string() + " --depth-scale -1");
  EXPECT_NE(negative.exit_code, 0);
  EXPECT_NE(negative.output.find("--depth-scale"), std::string::npos) << negative.output;
  const RunResult threads = run_gslam("reconstruct --out " + (dir / "a").string() + " --threads 1000");
  EXPECT_NE(threads.exit_code, 0);
  EXPECT_NE(threads.output.find("--threads"), std::string::npos) << threads.output;
  // A sequence whose depth is all zero (as a covered sensor gives): an error, not an empty run.
  app::SyntheticOptions o;
  o.frames = 4;
  app::write_synthetic_sequence(dir / "seq", o);
  for (const auto& entry : std::filesystem::directory_iterator(dir / "seq" / "depth")) {
    app::write_png_gray16(entry.path(), splat::Image16(o.width, o.height, 1, 0));
  }
  const RunResult empty = run_gslam("reconstruct " + (dir / "seq").string() + " --out " + (dir / "run").string());
  EXPECT_NE(empty.exit_code, 0);
  EXPECT_NE(empty.output.find("nothing was reconstructed: no frame of 4 had usable depth"), std::string::npos) << empty.output;
}

TEST(CliRender, RefusesRendersThatWouldNotFitInMemory) {
  TempDir dir;
  app::write_ply(dir / "map.ply", small_map());
  const RunResult orbit = run_gslam("render " + (dir / "map.ply").string() + " --out " + (dir / "o").string() + " --orbit 100000000");
  EXPECT_NE(orbit.exit_code, 0);
  EXPECT_NE(orbit.output.find("view count is 100000000, expected 1 to 100000"), std::string::npos) << orbit.output;
  const RunResult size = run_gslam("render " + (dir / "map.ply").string() + " --out " + (dir / "o").string() + " --size 16384x16384");
  EXPECT_NE(size.exit_code, 0);
  EXPECT_NE(size.output.find("268435456 pixels, expected at most 16777216"), std::string::npos) << size.output;
}

}  // namespace

namespace {

// Ctrl-C during reconstruct: it stops taking frames and writes complete outputs, saying so.
// The run is interrupted once its first frame is reported; it has 39 to go, each with heavy mapping.
TEST(CliReconstruct, CtrlCWritesCompleteOutputs) {
  TempDir dir;
  app::SyntheticOptions o;
  o.frames = 40;
  app::write_synthetic_sequence(dir / "seq", o);
  gslam::test::write_text(dir / "slow.json", R"({"mapping": {"iterations": 300}})");
  const auto r = gslam::test::run_and_interrupt(std::string(GSLAM_BINARY) + " reconstruct " + (dir / "seq").string() +
                                                    " --out " + (dir / "run").string() + " --config " + (dir / "slow.json").string(),
                                                "reconstruct 1/40");
  ASSERT_TRUE(r.event_seen) << r.output;
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("interrupted: writing what was done"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("continue with: gslam reconstruct --resume --out"), std::string::npos) << r.output;
  std::ifstream in(dir / "run" / "summary.json");
  const nlohmann::json s = nlohmann::json::parse(in);
  EXPECT_FALSE(s.at("complete").get<bool>()) << "an interrupted run can be resumed: it is not complete";
  EXPECT_TRUE(s.at("interrupted").get<bool>());
  EXPECT_NE(s.at("resume").get<std::string>().find("--resume"), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(dir / "run" / "checkpoint.bin"));
  EXPECT_LT(s.at("frames").get<std::size_t>(), 40u);
  EXPECT_GT(s.at("gaussians").get<std::size_t>(), 0u);
  EXPECT_TRUE(std::filesystem::exists(dir / "run" / "map.ply"));
  EXPECT_TRUE(std::filesystem::exists(dir / "run" / "map.glb"));
}

// Ctrl-C, then --resume: the run ends with the trajectory and map of a run never interrupted,
// wherever the interrupt fell (while taking frames or in the sweep).
TEST(CliReconstruct, ResumeAfterCtrlCEndsAsTheUninterruptedRun) {
  TempDir dir;
  app::SyntheticOptions o;
  o.frames = 16;
  app::write_synthetic_sequence(dir / "seq", o);
  gslam::test::write_text(dir / "slow.json", R"({"refine_passes": 2, "mapping": {"iterations": 60}})");
  const std::string args = " reconstruct " + (dir / "seq").string() + " --config " + (dir / "slow.json").string();
  ASSERT_EQ(run_gslam(args + " --out " + (dir / "straight").string()).exit_code, 0);
  const auto stopped = gslam::test::run_and_interrupt(std::string(GSLAM_BINARY) + args + " --out " + (dir / "resumed").string(),
                                                      "reconstruct 1/16");
  ASSERT_TRUE(stopped.event_seen) << stopped.output;
  ASSERT_EQ(stopped.exit_code, 0) << stopped.output;
  ASSERT_TRUE(std::filesystem::exists(dir / "resumed" / "checkpoint.bin")) << stopped.output;
  // A plain re-run into the folder names --resume; --resume takes no other input.
  const RunResult again = run_gslam(args + " --out " + (dir / "resumed").string());
  EXPECT_NE(again.exit_code, 0);
  EXPECT_NE(again.output.find("--resume"), std::string::npos) << again.output;
  const RunResult mixed = run_gslam(args + " --out " + (dir / "resumed").string() + " --resume");
  EXPECT_NE(mixed.exit_code, 0);
  EXPECT_NE(mixed.output.find("give only --out"), std::string::npos) << mixed.output;

  const RunResult resumed = run_gslam("reconstruct --resume --out " + (dir / "resumed").string());
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("resuming at frame"), std::string::npos) << resumed.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "resumed" / "checkpoint.bin")) << "a completed run keeps no checkpoint";
  EXPECT_EQ(gslam::test::read_text(dir / "resumed" / "trajectory.txt"), gslam::test::read_text(dir / "straight" / "trajectory.txt"));
  EXPECT_EQ(gslam::test::read_text(dir / "resumed" / "map.ply"), gslam::test::read_text(dir / "straight" / "map.ply"));
  std::ifstream in(dir / "resumed" / "summary.json");
  const nlohmann::json s = nlohmann::json::parse(in);
  EXPECT_FALSE(s.at("interrupted").get<bool>());
  EXPECT_EQ(s.at("frames").get<std::size_t>(), 16u);
  EXPECT_NO_THROW(app::check_run_manifest(dir / "resumed", s));
  const RunResult nothing_left = run_gslam("reconstruct --resume --out " + (dir / "resumed").string());
  EXPECT_NE(nothing_left.exit_code, 0);
  EXPECT_NE(nothing_left.output.find("no checkpoint to resume"), std::string::npos) << nothing_left.output;
}

}  // namespace

namespace {


// A run folder holds one run: a second run refuses it unless --overwrite, which clears the first
// run's files (and a killed run's temporaries); eval refuses a folder whose files mix runs.
TEST(CliReconstruct, RunFolderHoldsOneRun) {
  TempDir dir;
  write_quick_run_inputs(dir);
  const std::string args = "reconstruct " + (dir / "seq").string() + " --config " + (dir / "quick.json").string();
  ASSERT_EQ(run_gslam(args + " --out " + (dir / "a").string()).exit_code, 0);
  ASSERT_EQ(run_gslam(args + " --out " + (dir / "b").string() + " --max-frames 4").exit_code, 0);

  const RunResult again = run_gslam(args + " --out " + (dir / "a").string());
  EXPECT_NE(again.exit_code, 0);
  EXPECT_NE(again.output.find("holds another run's outputs"), std::string::npos) << again.output;
  EXPECT_NE(again.output.find("--overwrite"), std::string::npos) << again.output;

  gslam::test::write_text(dir / "a" / "keyframes" / ".kf_0009.tmp4242.exr", "partial");
  gslam::test::write_text(dir / "a" / "keyframes" / "kf_0099.png", "stale");
  const RunResult overwritten = run_gslam(args + " --out " + (dir / "a").string() + " --overwrite");
  ASSERT_EQ(overwritten.exit_code, 0) << overwritten.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "a" / "keyframes" / ".kf_0009.tmp4242.exr")) << "a killed run's temporary";
  EXPECT_FALSE(std::filesystem::exists(dir / "a" / "keyframes" / "kf_0099.png")) << "the old run's keyframe";

  const std::string eval = "eval " + (dir / "a").string() + " --dataset " + (dir / "seq").string();
  ASSERT_EQ(run_gslam(eval).exit_code, 0);
  std::filesystem::copy_file(dir / "b" / "map.ply", dir / "a" / "map.ply", std::filesystem::copy_options::overwrite_existing);
  const RunResult mixed = run_gslam(eval);
  EXPECT_NE(mixed.exit_code, 0);
  EXPECT_NE(mixed.output.find("map.ply: not the file run"), std::string::npos) << mixed.output;
  EXPECT_NE(mixed.output.find("the folder mixes runs"), std::string::npos) << mixed.output;
}

}  // namespace

namespace {

// A run records what it read (summary.json "input": dataset, camera, depth units, frames,
// configuration), and eval uses it: a run made with --intrinsics evaluates with no flags.
TEST(CliEval, UsesTheRunsRecordedDatasetAndIntrinsics) {
  TempDir dir;
  write_quick_run_inputs(dir);
  std::filesystem::remove(dir / "seq" / "intrinsics.txt");  // a camera the reader cannot know
  const std::string run = (dir / "run").string();
  const RunResult unknown = run_gslam("reconstruct " + (dir / "seq").string() + " --out " + run);
  ASSERT_NE(unknown.exit_code, 0) << "without intrinsics.txt the camera must be given";
  const RunResult made = run_gslam("reconstruct " + (dir / "seq").string() + " --out " + run + " --overwrite --intrinsics 260,260,160,120 --max-frames 5 --config " +
                                   (dir / "quick.json").string());
  ASSERT_EQ(made.exit_code, 0) << made.output;
  std::ifstream in(dir / "run" / "summary.json");
  const nlohmann::json input = nlohmann::json::parse(in).at("input");
  EXPECT_EQ(input.at("intrinsics").at("fx").get<double>(), 260);
  EXPECT_EQ(input.at("max_frames").get<int>(), 5);
  EXPECT_EQ(input.at("config").at("refine_passes").get<int>(), 1);
  const RunResult eval = run_gslam("eval " + run);
  ASSERT_EQ(eval.exit_code, 0) << eval.output;
  EXPECT_NE(eval.output.find("ATE RMSE"), std::string::npos) << eval.output;
}

// --test-every: the held-out frames are tracked (a pose each) but never keyframes, and eval
// scores them apart from the training views.
TEST(CliEval, ScoresHeldOutViewsApart) {
  TempDir dir;
  write_quick_run_inputs(dir);
  const std::string run = (dir / "run").string();
  const std::string args = "reconstruct " + (dir / "seq").string() + " --out " + run + " --config " + (dir / "quick.json").string();
  EXPECT_NE(run_gslam(args + " --test-every 1").exit_code, 0) << "every frame held out leaves nothing to map";
  const RunResult made = run_gslam(args + " --test-every 3");
  ASSERT_EQ(made.exit_code, 0) << made.output;
  std::ifstream summary_file(dir / "run" / "summary.json");
  const nlohmann::json summary = nlohmann::json::parse(summary_file);
  EXPECT_EQ(summary.at("held_out_frames").get<int>(), 2);  // frames 2 and 5 of 6
  EXPECT_EQ(summary.at("input").at("test_every").get<int>(), 3);
  EXPECT_FALSE(std::filesystem::exists(dir / "run" / "keyframes" / "kf_0002.png"));
  EXPECT_FALSE(std::filesystem::exists(dir / "run" / "keyframes" / "kf_0005.png"));
  EXPECT_EQ(summary.at("tracking_failures").get<int>(), 0);
  const RunResult eval = run_gslam("eval " + run);
  ASSERT_EQ(eval.exit_code, 0) << eval.output;
  EXPECT_NE(eval.output.find("held-out views (2)"), std::string::npos) << eval.output;
  std::ifstream eval_file(dir / "run" / "eval.json");
  const nlohmann::json j = nlohmann::json::parse(eval_file);
  EXPECT_EQ(j.at("held_out_rendering").at("frames").get<int>(), 2);
  EXPECT_EQ(j.at("rendering").at("frames").get<int>(), 4);
  EXPECT_GT(j.at("held_out_rendering").at("psnr_db").get<double>(), 15.0);
}

}  // namespace

namespace {

// EXR renders hold linear light premultiplied by alpha, PNG the display values composited over
// the background: EXR = srgb_to_linear((PNG - (1 - A) background) / A) A, to the PNG's 8-bit
// steps; nothing where A is 0.
TEST(CliRender, ExrIsLinearPremultipliedAgainstThePng) {
  TempDir dir;
  app::write_ply(dir / "map.ply", small_map());
  const RunResult r = run_gslam("render " + (dir / "map.ply").string() + " --out " + (dir / "out").string() +
                                " --orbit 1 --size 80x60 --format png,exr --backend cpu --background 0.2,0.4,0.6");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const splat::Image8 png = app::read_png_rgb8(dir / "out" / "view_0000.png");
  const app::ExrImage exr = app::read_exr(dir / "out" / "view_0000.exr");
  const auto& a = exr.channels.at("A");
  std::size_t covered = 0, empty = 0;
  for (std::size_t p = 0; p < a.size(); ++p) {
    for (int c = 0; c < 3; ++c) {
      const float linear = exr.channels.at(std::string(1, "RGB"[c]))[p];
      if (a[p] > 0.3f) {
        // The covered colour: the PNG's display value with the background taken off.
        const float bg = 0.2f * static_cast<float>(c + 1);
        const float display = png.data[p * 3 + c] / 255.f;
        const float x = (display - (1 - a[p]) * bg) / a[p], h = 0.5f / 255 / a[p];  // half an 8-bit step
        if (x - h < 0 || x + h > 1) continue;  // clamped in the PNG: no exact counterpart
        const float step = a[p] * (app::srgb_to_linear(x + h) - app::srgb_to_linear(x - h));
        EXPECT_NEAR(linear, app::srgb_to_linear(x) * a[p], step + 1e-6f) << "pixel " << p << " channel " << c;
        covered += c == 0;
      } else if (a[p] == 0.f) {
        EXPECT_EQ(linear, 0.f) << "no surface, no light (premultiplied), pixel " << p;
        empty += c == 0;
      }
    }
  }
  EXPECT_GT(covered, 50u);
  EXPECT_GT(empty, 50u);
}

}  // namespace
