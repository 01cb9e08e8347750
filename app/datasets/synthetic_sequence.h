#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <filesystem>

#include "datasets/lens_distortion.h"

namespace app {

struct SyntheticOptions {
  int frames = 60;
  // Frames the camera's path is spread over (0: `frames`); more than `frames` writes the start of
  // a longer sequence (a test's first second of a ten-second walk).
  int path_frames = 0;
  int width = 320, height = 240;
  double focal = 260;     // pixels; principal point at the image centre
  // A calibration error: intrinsics.txt says focal * (1 + focal_error), the images use focal.
  // Odometry then drifts as it does on real cameras, systematically.
  double focal_error = 0;
  // A lens that distorts (TUM's fr1 and fr2 Kinects): the images are seen through it, and
  // intrinsics.txt states it after the focal length and principal point.
  LensDistortion distortion;
  // Colour not registered to depth (7-Scenes, raw Kinect streams): the colour images are taken
  // from the depth camera's place through a focal length color_focal_ratio times the depth's and a
  // principal point shifted by color_centre_shift pixels; intrinsics.txt states the depth camera.
  double color_focal_ratio = 1;
  Eigen::Vector2d color_centre_shift = Eigen::Vector2d::Zero();
  double fps = 30;
  // 0: an arc through the room. N > 0: N laps of a circle about the room's middle, looking across
  // it, so the camera returns to where it began (loop closure's test).
  int laps = 0;
  // Two identical rooms one after the other along x, walked through from the first into the
  // second: a place that looks like one seen before and is not (a false loop to reject).
  bool twin_rooms = false;
  // A kidnapped camera: from frame kidnap_frame on, the path goes on from where it was at frame
  // kidnap_to (a jump back to a place seen earlier). 0: none.
  int kidnap_frame = 0, kidnap_to = 0;
  // Hard cases. A yaw oscillation on top of the arc, peaking at this rate (rad/s, at 1.5 Hz).
  double shake_peak_rate = 0;
  // Motion blur: colour averaged over this exposure (seconds) in blur_samples instants.
  double exposure = 0;
  int blur_samples = 1;
  // Depth noise: Gaussian, this many metres at 1 m, growing with z^2 (Kinect-like), then
  // quantized to the 1/5000 m PNG step; and holes: blobs covering about this fraction of the
  // pixels, plus every pixel whose surface is seen at more than 80 degrees.
  double depth_noise = 0;
  double depth_holes = 0;
  // Depth from a free-running camera (Kinect v1 in TUM's fr1/fr2): each depth image is taken up
  // to this many seconds before or after the colour image it pairs with, the offset drifting
  // through that range, and stamped with its own time. 0: taken together.
  double depth_lag = 0;
  // Rolling shutter (the CMOS sensors of Kinect-class cameras, colour and depth alike): the rows
  // are read top to bottom over this many seconds, each seen from the camera's pose at its own
  // instant; the frame's stamp and ground truth are its middle row's. 0: a global shutter.
  double rolling_shutter = 0;
  // Auto exposure hunting: the colour image's gain swings as exp(gain_swing sin(2 pi t / 3 s)),
  // its values clipped at 1 (saturated). 0: a fixed exposure.
  double gain_swing = 0;
  // Moving objects (for the arc path): a person walking across the view, a chair pushed a metre
  // and left, a crate that appears (see Movers in the .cpp), with depth lost along their edges.
  bool movers = false;
  // People walking through the whole sequence (for the arc path): two pacing to and fro across the
  // view, one near the camera, together often covering most of the image (see Walkers in the .cpp).
  bool walkers = false;
  // The walkers in patterned shirts, as most clothes are, rather than in stripes along their
  // walk: their motion then shows all over them, not only at their outlines.
  bool patterned_walkers = false;
  // Exact per-pixel class ids in labels/ (16-bit PNG, the colour images' names) with
  // labels/classes.json, which gslam then reads as the sequence's label images.
  bool labels = false;
  uint32_t seed = 1;
  // A hard-motion preset: 2.2 rad/s peaks, 1/60 s exposure, Kinect noise, 5% holes.
  static SyntheticOptions hard_motion();
};

// The colour image's gain at this time from the sequence's start (gain_swing).
double colour_gain(const SyntheticOptions& options, double seconds);

// Writes a synthetic RGB-D sequence in TUM layout (rgb/, depth/ as 16-bit PNG / 5000,
// rgb.txt, depth.txt, groundtruth.txt and intrinsics.txt) with exact ground truth (and labels). The images
// come from a ray caster of a textured room with spheres and boxes, independent of the splat
// renderer, so reconstruction is never tested on its own image model. Deterministic.
void write_synthetic_sequence(const std::filesystem::path& dir, const SyntheticOptions& options);

// Whether world point `p` lies, by more than `margin` metres, inside space that
// SyntheticOptions::movers' person and chair passed through, that they leave empty by 4.7 s, and
// that the arc's camera then sees empty (a map of a sequence at least that long should hold
// nothing there: what it holds are ghosts).
bool swept_by_movers(const Eigen::Vector3d& p, double margin);

}  // namespace app
