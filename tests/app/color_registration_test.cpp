// Colour not registered to depth: the resampling checked against the pinhole model written out
// here, the estimate against the generator's colour camera (a ray caster of its own), and the
// colour camera recorded by a run so that eval and --resume load the same colour.
#include "datasets/color_registration.h"

#include <gtest/gtest.h>

#include <cmath>

#include "commands/run_input.h"
#include "datasets/dataset.h"
#include "datasets/synthetic_sequence.h"
#include "support/expect_error.h"
#include "support/temp_dir.h"

namespace {

using gslam::test::TempDir;

splat::Camera depth_camera() {
  splat::Camera c;
  c.fx = 260, c.fy = 258, c.cx = 160.5, c.cy = 119.5;
  c.width = 320, c.height = 240;
  return c;
}

// A smooth colour in the colour camera's pixel coordinates (centres at +0.5).
double colour_at(double u, double v) { return 0.5 + 0.4 * std::sin(0.05 * u) * std::cos(0.07 * v); }

splat::RgbdFrame colour_frame(const splat::Camera& camera) {
  splat::RgbdFrame f;
  f.camera = camera;
  f.rgb.resize(static_cast<std::size_t>(camera.width) * camera.height * 3);
  f.depth.assign(static_cast<std::size_t>(camera.width) * camera.height, 1.f);
  for (int y = 0; y < camera.height; ++y) {
    for (int x = 0; x < camera.width; ++x) {
      for (int c = 0; c < 3; ++c) {
        f.rgb[(static_cast<std::size_t>(y) * camera.width + x) * 3 + c] = static_cast<float>(colour_at(x + 0.5, y + 0.5));
      }
    }
  }
  return f;
}

TEST(ColorRegistration, ResamplesTheColourCameraIntoTheDepthCamerasPixels) {
  const splat::Camera depth = depth_camera();
  // A wider colour view (7-Scenes' Kinect): every depth pixel has colour.
  const app::ColorCamera color{234, 232.2, 156.5, 120.5};
  splat::RgbdFrame f = colour_frame(depth);
  app::ColorResampler(depth, color).apply(f);
  double worst = 0;
  for (int y = 0; y < depth.height; ++y) {
    for (int x = 0; x < depth.width; ++x) {
      // The ray through depth pixel (x, y), seen by the colour camera.
      const double nx = (x + 0.5 - depth.cx) / depth.fx, ny = (y + 0.5 - depth.cy) / depth.fy;
      const double expected = colour_at(color.fx * nx + color.cx, color.fy * ny + color.cy);
      worst = std::max(worst, std::abs(f.rgb[(static_cast<std::size_t>(y) * depth.width + x) * 3 + 1] - expected));
    }
  }
  EXPECT_LT(worst, 2e-3) << "bilinear interpolation of a smooth image";
  EXPECT_TRUE(f.ignore.empty()) << "no pixel lies outside the colour view";

  // A narrower colour view: the depth pixels around the border see no colour and are ignored.
  splat::RgbdFrame narrow = colour_frame(depth);
  app::ColorResampler(depth, {300, 300, 160, 120}).apply(narrow);
  ASSERT_EQ(narrow.ignore.size(), narrow.depth.size());
  EXPECT_EQ(narrow.ignore[0], 1) << "corner";
  EXPECT_EQ(narrow.ignore[static_cast<std::size_t>(120) * depth.width + 160], 0) << "centre";

  splat::RgbdFrame small = colour_frame(depth);
  small.camera.width = 100;
  GSLAM_EXPECT_ERROR(app::ColorResampler(depth, color).apply(small), "colour registration", "320x240");
}

TEST(ColorRegistration, ColourCameraTextIsAutoRegisteredOrFourNumbers) {
  EXPECT_EQ(app::parse_color_camera("").kind, app::ColorCameraChoice::kAuto);
  EXPECT_EQ(app::parse_color_camera("auto").kind, app::ColorCameraChoice::kAuto);
  EXPECT_EQ(app::parse_color_camera("registered").kind, app::ColorCameraChoice::kRegistered);
  const app::ColorCameraChoice given = app::parse_color_camera("525,524,319.5,239.5");
  EXPECT_EQ(given.kind, app::ColorCameraChoice::kGiven);
  EXPECT_EQ(given.given.text(), "525,524,319.5,239.5");
  for (const char* bad : {"525,525,320", "525,525,320,240,1", "0,525,320,240", "nan,525,320,240", "fast"}) {
    const std::string quoted = std::string("--color-camera '") + bad + "'";
    GSLAM_EXPECT_ERROR(app::parse_color_camera(bad), quoted.c_str(), "fx,fy,cx,cy");
  }
}

// The generator's colour through a focal length 0.9x the depth camera's and a principal point
// 4 px left, 1 px down (7-Scenes' raw colour at half its size).
app::SyntheticOptions unregistered_sequence() {
  app::SyntheticOptions o;
  o.frames = 16;
  o.shake_peak_rate = 1.0;
  o.depth_noise = 0.0015;
  o.color_focal_ratio = 0.9;
  o.color_centre_shift = {-4, 1};
  return o;
}

double mean_colour_difference(const splat::RgbdFrame& a, const splat::RgbdFrame& b) {
  double sum = 0;
  for (std::size_t i = 0; i < a.rgb.size(); ++i) sum += std::abs(a.rgb[i] - b.rgb[i]);
  return sum / static_cast<double>(a.rgb.size());
}

TEST(ColorRegistration, EstimateFindsTheColourCameraAndRegistersItsFrames) {
  TempDir dir;
  app::SyntheticOptions o = unregistered_sequence();
  app::write_synthetic_sequence(dir / "raw", o);
  o.color_focal_ratio = 1, o.color_centre_shift.setZero();
  app::write_synthetic_sequence(dir / "registered", o);

  const app::Dataset raw = app::open_dataset(dir / "raw");
  ASSERT_TRUE(raw.color_estimate);
  ASSERT_TRUE(raw.color_registration) << "gain " << raw.color_estimate->gain;
  const app::ColorCamera& found = raw.color_registration->color_camera();
  EXPECT_NEAR(found.fx, 0.9 * 260, 0.005 * 260);
  EXPECT_NEAR(found.fy, 0.9 * 260, 0.005 * 260);
  EXPECT_NEAR(found.cx, 160 - 4, 0.5);
  EXPECT_NEAR(found.cy, 120 + 1, 0.5);
  EXPECT_NE(raw.color_note().find("not registered to depth"), std::string::npos) << raw.color_note();

  // Registered colour: left as it is.
  const app::Dataset registered = app::open_dataset(dir / "registered");
  ASSERT_TRUE(registered.color_estimate);
  EXPECT_FALSE(registered.color_registration) << "gain " << registered.color_estimate->gain;
  EXPECT_LT(registered.color_estimate->gain, app::ColorCameraEstimate::kMinGain);
  EXPECT_EQ(registered.color_note(), "");

  // The raw sequence's frames, registered, show what the registered sequence's show.
  app::DatasetOptions as_is;
  as_is.color_camera = "registered";
  const app::Dataset unchanged = app::open_dataset(dir / "raw", as_is);
  EXPECT_FALSE(unchanged.color_registration);
  const splat::RgbdFrame truth = registered.load(8);
  const double after = mean_colour_difference(raw.load(8), truth);
  const double before = mean_colour_difference(unchanged.load(8), truth);
  EXPECT_LT(after, 0.3 * before) << "mean |colour difference| " << after << " registered, " << before << " raw";

  // A run records the colour camera; the recorded input loads the same colour without estimating.
  const app::RecordedInput recorded =
      app::recorded_input(app::run_input_json(dir / "raw", raw, 0, 0, app::SlamConfig{}), "summary.json");
  EXPECT_EQ(recorded.options.color_camera, found.text());
  const app::Dataset again = app::open_dataset(dir / "raw", recorded.options);
  EXPECT_FALSE(again.color_estimate) << "given, not estimated";
  ASSERT_TRUE(again.color_registration);
  EXPECT_EQ(again.color_registration->color_camera().text(), found.text());
  const app::RecordedInput plain = app::recorded_input(
      app::run_input_json(dir / "registered", registered, 0, 0, app::SlamConfig{}), "summary.json");
  EXPECT_EQ(plain.options.color_camera, "registered");
  nlohmann::json older = app::run_input_json(dir / "raw", raw, 0, 0, app::SlamConfig{});
  older.erase("color_camera");
  EXPECT_EQ(app::recorded_input(older, "summary.json").options.color_camera, "registered")
      << "runs from before registration loaded colour as it is";
}

TEST(ColorRegistration, FramesWithoutDepthEdgesKeepTheirColour) {
  // A flat wall facing the camera: no depth edge to align colour with.
  splat::RgbdFrame wall = colour_frame(depth_camera());
  const std::vector<splat::RgbdFrame> frames(3, wall);
  const app::ColorCameraEstimate e = app::estimate_color_camera(frames);
  EXPECT_EQ(e.edge_points, 0u);
  EXPECT_FALSE(e.register_color);
  EXPECT_EQ(e.camera.text(), app::ColorCamera({260, 258, 160.5, 119.5}).text());
}

}  // namespace
