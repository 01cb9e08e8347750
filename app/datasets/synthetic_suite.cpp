#include "datasets/synthetic_suite.h"

namespace app {

std::vector<SyntheticCase> hard_case_suite() {
  std::vector<SyntheticCase> suite;
  auto add = [&](std::string name, std::string what, SyntheticOptions o) {
    suite.push_back({std::move(name), std::move(what), o});
  };
  SyntheticOptions o;
  o.frames = 200;
  o.shake_peak_rate = 0.3;
  add("slow_shake", "200 frames, yaw shake peaking at 0.3 rad/s", o);

  o = SyntheticOptions::hard_motion();
  o.frames = 200;
  add("fast_rotation", "200 frames, 2.2 rad/s, 1/60 s exposure, Kinect noise, 5% holes", o);

  o.depth_lag = 0.015;
  add("unsynced_depth", "fast_rotation with each depth image up to 15 ms before or after its colour (Kinect v1)", o);
  o.depth_lag = 0;

  o.rolling_shutter = 0.028;
  add("rolling_shutter",
      "fast_rotation through rolling-shutter colour and depth, rows read over 28 ms (Kinect class)", o);
  o.rolling_shutter = 0;

  o.gain_swing = 0.3;
  add("exposure_swing",
      "fast_rotation with the colour gain swinging from 0.74x to 1.35x every 3 s (auto exposure)",
      o);
  o.gain_swing = 0;

  o.shake_peak_rate = 3.0;
  o.exposure = 1.0 / 30;
  o.depth_holes = 0.15;
  add("blur_and_holes", "200 frames, 3 rad/s, 1/30 s exposure, Kinect noise, 15% holes", o);

  o = SyntheticOptions{};
  o.frames = 200;
  o.shake_peak_rate = 1.0;
  o.depth_noise = 0.0015;
  o.distortion = {0.262383, -0.953104, -0.005358, 0.002628, 1.163314};
  add("lens_distortion",
      "200 frames, 1 rad/s, Kinect noise, raw images through TUM fr1's lens (intrinsics.txt states "
      "it)",
      o);

  o = SyntheticOptions{};
  o.frames = 200;
  o.shake_peak_rate = 1.0;
  o.depth_noise = 0.0015;
  o.color_focal_ratio = 0.9;
  o.color_centre_shift = {-4, 1};
  add("unregistered_color",
      "200 frames, 1 rad/s, Kinect noise, colour through a focal length 0.9x depth's and a principal point "
      "4 px off (7-Scenes' raw colour)",
      o);

  o = SyntheticOptions{};
  o.frames = 300;
  o.laps = 1;
  o.focal_error = 0.01;
  add("loop_focal_error", "300 frames, one lap back to the start, focal length 1% off", o);

  o = SyntheticOptions{};
  o.frames = 300;
  o.laps = 1;
  o.shake_peak_rate = 2.0;
  o.exposure = 1.0 / 30;
  o.blur_samples = 4;
  add("loop_blur", "300 frames, one lap, 2 rad/s, 1/30 s exposure", o);

  o = SyntheticOptions{};
  o.frames = 700;
  o.laps = 2;
  o.shake_peak_rate = 0.5;
  o.depth_noise = 0.0015;
  add("long_two_laps", "700 frames, two laps, 0.5 rad/s, Kinect noise", o);

  o = SyntheticOptions{};
  o.frames = 150;
  o.movers = true;
  o.depth_noise = 0.0015;
  add("moving_objects", "150 frames, a person walking across, a chair pushed 1 m, a crate appearing; Kinect noise", o);

  o = SyntheticOptions{};
  o.frames = 300;
  o.walkers = true;
  o.depth_noise = 0.0015;
  add("walkers",
      "300 frames, two people pacing across the view throughout, one 0.6 m from the camera; Kinect "
      "noise",
      o);

  o.patterned_walkers = true;
  add("walkers_patterned", "walkers in patterned shirts: their motion shows all over them, not only at their outlines", o);
  return suite;
}

}  // namespace app
