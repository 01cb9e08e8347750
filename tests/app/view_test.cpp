// `gslam view`: the picture it composes for a map and its cameras, how the view moves, and the
// real window under Xvfb.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <memory>

#include "app/run_gslam.h"
#include "datasets/synthetic_sequence.h"
#include "io/image_io.h"
#include "splat/error.h"
#include "support/expect_error.h"
#include "support/random_scene.h"
#include "support/image_counts.h"
#include "support/temp_dir.h"
#include "viewer/live_view.h"
#include "viewer/map_view.h"

namespace {

using gslam::test::count_colour;
using gslam::test::count_map_pixels;
using gslam::test::TempDir;

// A random map, seen by three recorded cameras: the scene's own, one 0.3 m to its left and
// one 0.5 m behind that.
struct Fixture {
  gslam::test::Scene<float> random;
  app::MapScene scene;
};

Fixture make_fixture() {
  gslam::test::SceneOptions o;
  o.count = 300;
  o.max_opacity = 0.95;
  Fixture f{gslam::test::make_random_scene<float>(o), {}};
  const Eigen::Isometry3d T0 = f.random.camera.T_cam_world.inverse();
  const Eigen::Isometry3d T1 = T0 * Eigen::Translation3d(-0.3, 0, 0);
  const Eigen::Isometry3d T2 = T1 * Eigen::Translation3d(0, 0, -0.5);
  const splat::Camera& c = f.random.camera;
  const app::Intrinsics k{c.fx, c.fy, c.cx, c.cy, c.width, c.height};
  const std::vector<Eigen::Isometry3d> cameras{T0, T1, T2};
  f.scene =
      app::make_map_scene(f.random.gaussians, cameras, {0.0, 0.1, 0.2}, k, app::camera_up(cameras));
  return f;
}

TEST(MapView, OverviewShowsMapCamerasAndTrajectory) {
  const Fixture f = make_fixture();
  auto rasterizer = splat::make_cpu_rasterizer({1});
  const splat::Image8 picture =
      app::compose_map_view(f.scene, app::overview_view(f.scene), *rasterizer);
  ASSERT_EQ(picture.width, app::kMapViewWidth);
  ASSERT_EQ(picture.height, app::kMapViewHeight);
  EXPECT_GT(count_map_pixels(picture), 5000) << "the map should fill part of the picture";
  EXPECT_GT(count_colour(picture, app::kCameraMarkerRgb), 60) << "camera frusta not drawn";
  EXPECT_GT(count_colour(picture, app::kTrajectoryRgb), 10) << "trajectory not drawn";
  // At half resolution the picture has the same size and still shows the map.
  const splat::Image8 quick =
      app::compose_map_view(f.scene, app::overview_view(f.scene), *rasterizer, 2);
  ASSERT_EQ(quick.width, app::kMapViewWidth);
  EXPECT_GT(count_map_pixels(quick), 5000) << "half-resolution picture";
}

TEST(MapView, JumpingToACameraRendersFromItsPoseWithItsIntrinsics) {
  const Fixture f = make_fixture();
  auto rasterizer = splat::make_cpu_rasterizer({1});
  for (int i = 0; i < 3; ++i) {
    const app::MapViewCamera view = app::recorded_view(f.scene, i);
    EXPECT_EQ(view.camera, i);
    EXPECT_TRUE(view.T_world_view.isApprox(f.scene.cameras[static_cast<std::size_t>(i)], 1e-12))
        << "camera " << i;
    // The 64x48 camera scaled 12.5 times fills the 800x600 picture exactly.
    splat::Camera expected = f.random.camera;
    for (double* v : {&expected.fx, &expected.fy, &expected.cx, &expected.cy}) *v *= 12.5;
    expected.width = app::kMapViewWidth;
    expected.height = app::kMapViewHeight;
    expected.T_cam_world = f.scene.cameras[static_cast<std::size_t>(i)].inverse();
    const splat::Camera cam = app::render_camera(view, f.scene);
    EXPECT_NEAR(cam.fx, expected.fx, 1e-9) << "camera " << i;
    EXPECT_NEAR(cam.cx, expected.cx, 1e-9) << "camera " << i;
    expected.near = cam.near;
    splat::RenderSettings settings;
    settings.background = {0.1f, 0.1f, 0.1f};
    const splat::ForwardResult direct = rasterizer->forward(f.scene.map, expected, settings);
    const splat::Image8 picture = app::compose_map_view(f.scene, view, *rasterizer);
    std::size_t same = 0;
    for (int y = 0; y < picture.height; ++y) {
      for (int x = 0; x < picture.width; ++x) {
        bool equal = true;
        for (int c = 0; c < 3; ++c) {
          const float v = direct.rgb[(static_cast<std::size_t>(y) * picture.width + x) * 3 +
                                     static_cast<std::size_t>(c)];
          equal = equal && picture.at(x, y, c) ==
                               static_cast<uint8_t>(std::clamp(v, 0.f, 1.f) * 255.f + 0.5f);
        }
        same += equal;
      }
    }
    // Everything but the other cameras' frusta and the trajectory drawn over the render.
    EXPECT_GT(static_cast<double>(same) / static_cast<double>(picture.pixels()), 0.95)
        << "camera " << i;
    EXPECT_GT(count_map_pixels(picture), 20000) << "camera " << i;
  }
  GSLAM_EXPECT_ERROR(app::recorded_view(f.scene, 3), "camera 3 is not recorded", "expected 0 to 2");
  GSLAM_EXPECT_ERROR(app::recorded_view(f.scene, -1), "camera -1 is not recorded");
}

TEST(MapView, OrbitPanZoomAndFlyMoveTheViewTheExpectedWay) {
  const Fixture f = make_fixture();
  const app::MapViewCamera start = app::recorded_view(f.scene, 0);
  const Eigen::Vector3d eye = start.T_world_view.translation();
  const Eigen::Vector3d x = start.T_world_view.linear().col(0),
                        y = start.T_world_view.linear().col(1),
                        z = start.T_world_view.linear().col(2);
  const Eigen::Vector3d& up = f.scene.up;
  const double d0 = (start.pivot - eye).norm();
  ASSERT_GT(d0, 0);
  auto moved = [&](const app::MapViewCamera& v) {
    return Eigen::Vector3d(v.T_world_view.translation() - eye);
  };

  {  // Dragging right pans the scene right: the view moves to its left, the pivot with it.
    app::MapViewCamera v = start;
    app::pan_view(v, 40, 0);
    EXPECT_LT(moved(v).dot(x), -1e-3);
    EXPECT_NEAR(moved(v).dot(y), 0, 1e-9);
    EXPECT_NEAR(moved(v).dot(z), 0, 1e-9);
    EXPECT_TRUE((v.pivot - start.pivot).isApprox(moved(v), 1e-9));
    EXPECT_EQ(v.camera, -1) << "a moved view shows no recorded camera";
    app::MapViewCamera w = start;
    app::pan_view(w, 0, 40);  // dragging down: the view rises (image y points down)
    EXPECT_LT(moved(w).dot(y), -1e-3);
    EXPECT_NEAR(moved(w).dot(x), 0, 1e-9);
  }
  {  // Fly: right along the view's x, up along the world's up, forward along its axis.
    app::MapViewCamera v = start;
    app::fly_view(v, f.scene, Eigen::Vector3d(0, 0, 0.5));
    EXPECT_TRUE(moved(v).isApprox(0.5 * z, 1e-9)) << moved(v).transpose();
    v = start;
    app::fly_view(v, f.scene, Eigen::Vector3d(0.2, 0, 0));
    EXPECT_TRUE(moved(v).isApprox(0.2 * x, 1e-9)) << moved(v).transpose();
    v = start;
    app::fly_view(v, f.scene, Eigen::Vector3d(0, -0.3, 0));
    EXPECT_TRUE(moved(v).isApprox(-0.3 * up, 1e-9)) << moved(v).transpose();
    EXPECT_TRUE(v.T_world_view.linear().isApprox(start.T_world_view.linear(), 1e-12))
        << "fly does not turn";
    EXPECT_EQ(v.camera, -1);
  }
  {  // Zoom: 10% of the distance to the pivot a step, along the axis; the pivot stays.
    app::MapViewCamera v = start;
    app::zoom_view(v, f.scene, 3);
    EXPECT_NEAR((v.pivot - v.T_world_view.translation()).norm(), d0 * 0.729, 1e-9);
    EXPECT_TRUE(v.pivot.isApprox(start.pivot, 1e-12));
    EXPECT_GT(moved(v).dot(z), 0) << "zooming in moves forward";
    app::zoom_view(v, f.scene, -3);
    EXPECT_TRUE(v.T_world_view.translation().isApprox(eye, 1e-9)) << "zooming out again comes back";
  }
  {  // Orbit: about the pivot, at the same distance, still looking at it.
    app::MapViewCamera v = start;
    app::orbit_view(v, f.scene, 30, 0);
    const Eigen::Vector3d offset = v.T_world_view.translation() - v.pivot;
    EXPECT_NEAR(offset.norm(), d0, 1e-9);
    EXPECT_TRUE(v.T_world_view.linear().col(2).isApprox(-offset.normalized(), 1e-9))
        << "looks at the pivot";
    EXPECT_LT(moved(v).dot(x), -1e-3) << "dragging right turns the scene right: the view goes left";
    EXPECT_NEAR((v.T_world_view.translation() - v.pivot).dot(up), (eye - start.pivot).dot(up), 1e-9)
        << "a sideways drag keeps the height";
    app::MapViewCamera w = start;
    app::orbit_view(w, f.scene, 0, 30);
    EXPECT_GT((w.T_world_view.translation() - w.pivot).dot(up), (eye - start.pivot).dot(up) + 1e-3)
        << "dragging down raises the view";
    app::orbit_view(w, f.scene, 0, 1e5);
    EXPECT_LE((w.T_world_view.translation() - w.pivot).normalized().dot(up),
              std::sin(85.0 * M_PI / 180.0) + 1e-9)
        << "elevation stops short of the pole";
  }
  {  // The overview looks at the map's centre from outside the cameras.
    const app::MapViewCamera v = app::overview_view(f.scene);
    EXPECT_TRUE(v.pivot.isApprox(f.scene.extent.center, 1e-12));
    EXPECT_EQ(v.camera, -1);
    for (const auto& T : f.scene.cameras) {
      EXPECT_GT((v.T_world_view.translation() - v.pivot).norm(),
                (T.translation() - v.pivot).norm());
    }
  }
}

TEST(MapView, SceneChecksItsInputs) {
  gslam::test::SceneOptions o;
  const auto random = gslam::test::make_random_scene<float>(o);
  GSLAM_EXPECT_ERROR(app::make_map_scene({}, {}, {}, std::nullopt, Eigen::Vector3d::UnitZ()),
                     "no Gaussians");
  GSLAM_EXPECT_ERROR(
      app::make_map_scene(random.gaussians, {}, {}, std::nullopt, Eigen::Vector3d::Zero()), "up");
  GSLAM_EXPECT_ERROR(app::make_map_scene(random.gaussians, {Eigen::Isometry3d::Identity()},
                                         {0.0, 1.0}, std::nullopt, Eigen::Vector3d::UnitZ()),
                     "2 timestamps for 1 cameras");
  const app::MapScene bare =
      app::make_map_scene(random.gaussians, {}, {}, std::nullopt, Eigen::Vector3d(0, 0, 2));
  EXPECT_TRUE(bare.up.isApprox(Eigen::Vector3d::UnitZ()));
  GSLAM_EXPECT_ERROR(app::recorded_view(bare, 0), "the map has no cameras");
}

// One short reconstruct run shared by the command-line tests.
class CliView : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = std::make_unique<TempDir>();
    app::SyntheticOptions o;
    o.frames = 8;
    app::write_synthetic_sequence(*dir_ / "seq", o);
    std::ofstream(*dir_ / "config.json") << R"({"refine_passes": 0})";
    const auto r = run_gslam("reconstruct " + (*dir_ / "seq").string() + " --out " +
                             run().string() + " --config " + (*dir_ / "config.json").string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  static void TearDownTestSuite() { dir_.reset(); }
  static std::filesystem::path run() { return *dir_ / "run"; }
  static std::unique_ptr<TempDir> dir_;

  // `gslam view ARGS --screenshot` in a virtual display; the picture, or an empty one.
  static splat::Image8 screenshot(const std::string& args, const std::string& name) {
    const std::filesystem::path shot = *dir_ / name;
    // Leak checking off for this process only, as in CliLive: Mesa's GLX driver leaves 112
    // bytes LeakSanitizer cannot attribute once glfwTerminate unloads it.
    const auto r = gslam::test::run_command(
        "ASAN_OPTIONS=detect_leaks=0 xvfb-run -a -s '-screen 0 1280x1024x24' " +
        std::string(GSLAM_BINARY) + " view " + args + " --backend cpu --screenshot " +
        shot.string());
    EXPECT_EQ(r.exit_code, 0) << r.output;
    if (r.exit_code != 0 || !std::filesystem::exists(shot)) return {};
    return app::read_png_rgb8(shot);
  }
};
std::unique_ptr<TempDir> CliView::dir_;

TEST_F(CliView, ScreenshotOfARunFolderShowsTheMapAndItsCameras) {
  if (!gslam::test::program_available("xvfb-run"))
    GTEST_SKIP() << "xvfb-run not found (apt-get install xvfb xauth)";
  const splat::Image8 overview = screenshot(run().string(), "overview.png");
  ASSERT_EQ(overview.width, app::kMapViewWidth);
  ASSERT_EQ(overview.height, app::kMapViewHeight);
  EXPECT_GT(count_map_pixels(overview), 20000) << "map not drawn";
  EXPECT_GT(count_colour(overview, app::kCameraMarkerRgb), 20) << "camera frusta not drawn";
  // From recorded camera 3 the map fills the picture.
  const splat::Image8 at_camera = screenshot(run().string() + " --camera 3", "camera3.png");
  ASSERT_EQ(at_camera.width, app::kMapViewWidth);
  EXPECT_GT(count_map_pixels(at_camera), 200000) << "the map seen from a recorded camera";
}

TEST_F(CliView, ScreenshotOfABareMapShowsIt) {
  if (!gslam::test::program_available("xvfb-run"))
    GTEST_SKIP() << "xvfb-run not found (apt-get install xvfb xauth)";
  for (const std::string& map :
       {std::string(GSLAM_SOURCE_DIR) + "/assets/demo_map.ply", (run() / "map.glb").string()}) {
    const splat::Image8 picture = screenshot(map, "bare.png");
    ASSERT_EQ(picture.width, app::kMapViewWidth) << map;
    EXPECT_GT(count_map_pixels(picture), 10000) << map;
    EXPECT_EQ(count_colour(picture, app::kCameraMarkerRgb), 0)
        << map << ": a bare map has no cameras";
  }
}

TEST_F(CliView, ErrorsAreOneLineNamingTheCause) {
  const std::string missing = (*dir_ / "nowhere.ply").string();
  const auto r = run_gslam("view " + missing);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(r.output, "error: " + missing + ": no such file or folder\n");
  const auto empty_folder = run_gslam("view " + (*dir_ / "seq").string());
  EXPECT_NE(empty_folder.exit_code, 0);
  EXPECT_NE(
      empty_folder.output.find("error: " + (*dir_ / "seq" / "map.ply").string() + ": no such file"),
      std::string::npos)
      << empty_folder.output;
  const auto camera = run_gslam("view " + run().string() + " --camera 99");
  EXPECT_NE(camera.exit_code, 0);
  EXPECT_NE(camera.output.find("error: view: camera 99 is not recorded, expected 0 to 7"),
            std::string::npos)
      << camera.output;
  const auto up = run_gslam("view " + run().string() + " --up 0,0");
  EXPECT_NE(up.exit_code, 0);
  EXPECT_NE(up.output.find("--up"), std::string::npos) << up.output;
  // No display (DISPLAY and WAYLAND_DISPLAY unset): the window's error is the only line.
  const auto headless = gslam::test::run_command(
      "env -u DISPLAY -u WAYLAND_DISPLAY " + std::string(GSLAM_BINARY) + " view " + run().string());
  EXPECT_NE(headless.exit_code, 0);
  EXPECT_EQ(headless.output.rfind("error: viewer: ", 0), 0u) << headless.output;
  EXPECT_EQ(std::count(headless.output.begin(), headless.output.end(), '\n'), 1) << headless.output;
}

}  // namespace
