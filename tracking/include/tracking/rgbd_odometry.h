// Dense direct RGB-D odometry (in the manner of DVO, Kerl et al. 2013): the pose of a new frame
// relative to a reference keyframe, from the reference's own colour and depth, by Gauss-Newton
// on se(3) over image pyramids. Its cost per frame depends on the image size, never on the map.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "splat/rgbd_frame.h"

namespace tracking {

struct OdometryConfig {
  // Coarse to fine, each level half the size of the next, with its iteration budget (coarsest
  // first). The finest level is the input halved until it is at most finest_width wide: at
  // 640x480, 320x240, 160x120 and 80x60. Full resolution added little for 4x the pixels.
  std::vector<int> iterations = {12, 10, 8};
  int finest_width = 320;
  // Points used per level: pixels with measured depth, at most this many, the ones with the
  // largest intensity or depth gradients first (flat pixels carry no information).
  int max_points = 3000;  // 6000 cost 12 against 8 ms a frame for the same teddy ATE
  // Photometric residuals in [0, 1] intensity, depth residuals in metres scaled by the sensor's
  // noise at that depth (depth_noise z^2): both unitless, then weighted by the t-distribution
  // (DVO: nu = 5) with its scale re-estimated every iteration, so outliers (occlusions, moving
  // objects, unregistered colour) lose weight.
  double depth_noise = 0.0015;  // metres at 1 m (Kinect-class: ~1.5 mm at 1 m, ~2.4 cm at 4 m)
  double t_dof = 5;
  // Depth relative to the photometric term on a sharp frame. Colour is the more precise of the
  // two there, but motion blur makes it lie and then depth is what holds: where the tracker knows
  // the camera's angular rate (blur_aware_depth_weight), the weight grows as
  // depth_weight * (1 + (blur / blur_scale_px)^2), blur = the finest level's focal * rate *
  // exposure in pixels (docs/tuning.md: measured on both real and six generated sequences).
  double depth_weight = 0.2;
  double blur_scale_px = 2.5;  // 0: the weight stays depth_weight whatever the motion
  double exposure = 1.0 / 60;  // seconds: a Kinect-class colour camera indoors
  // The SLAM system measures the exposure from the frames (exposure_estimate.h), with
  // `exposure` as the prior and unit: fade_per_blur_px is how fast frames lose gradient along
  // their motion per pixel of blur at `exposure` (the generator's sequences at 1/60 s), over
  // the last exposure_window tracked frames.
  bool estimate_exposure = true;
  double fade_per_blur_px = 0.2;
  int exposure_window = 150;
  // The colour camera's exposure and gain change between frames (auto exposure): the
  // photometric residual compares the current frame with gain x reference, the gain fitted
  // robustly where the coarsest level starts and again where each coarser level ends.
  bool estimate_brightness = true;
  // Rolling shutter: the camera reads its rows top to bottom over this many seconds (colour and
  // depth alike), each row seen from the camera's pose at its own instant. With the camera's
  // motion during the frames (align_rgbd's `twist`) each point is moved to where the frame's
  // middle row saw it, the instant its pose is. 0: a global shutter.
  double rolling_shutter = 0;
  double min_depth = 0.1, max_depth = 8.0;  // metres: measurements outside are ignored
  // Reference points are taken away from depth edges (depth changing by more than this fraction
  // per pixel) and holes: tracking_bench, teddy 0.79 -> 0.47 cm, 7-Scenes 3.06 -> 2.67 cm; at
  // 0.002 too few points were left on 7-Scenes and it lost track.
  double max_depth_slope = 0.01;
  // A level ends when a step moves less than this (metres, radians).
  double min_step_translation = 1e-5, min_step_rotation = 1e-5;
  // Failure: too few reference points land inside the new frame with depth there (overlap), or
  // the Hessian is near singular (degenerate geometry and texture: a smallest eigenvalue below
  // this fraction of the largest).
  double min_overlap = 0.3;
  double min_conditioning = 1e-7;
  void validate(const std::string& prefix = "OdometryConfig.") const;
};

// A frame prepared for alignment: per pyramid level its intensity, depth and their gradients.
class OdometryFrame {
 public:
  // Pixels left out besides the frame's own ignore mask: `reasons` (splat::RgbdFrame::ignore's
  // values, 0 for none), one per `factor` x `factor` block of the frame (blocks of the last row
  // and column also cover the remainder), or empty. Taken apart from the frame so that masking
  // it needs no copy of its images.
  struct LeftOut {
    std::vector<uint8_t> reasons;
    int factor = 1;
  };
  // Throws splat::Error if the frame's images, or `left_out`, do not match its camera.
  OdometryFrame(const splat::RgbdFrame& frame, const OdometryConfig& config,
                const LeftOut& left_out);
  OdometryFrame(const splat::RgbdFrame& frame, const OdometryConfig& config);
  struct Level {
    int width = 0, height = 0;
    double fx = 0, fy = 0, cx = 0, cy = 0;  // pixel centres at +0.5 as splat::Camera
    std::vector<float> intensity, depth;    // [H, W]
    std::vector<float> intensity_dx, intensity_dy, depth_dx, depth_dy;  // per pixel
    // The frame's ignored pixels (splat::RgbdFrame::ignore) at this level, or empty: no point is
    // taken there, and no residual where a reference point lands there.
    std::vector<uint8_t> ignore;
    // The selected points of this level when the frame is a reference: pixel index and its
    // 3D position in the camera.
    std::vector<int> points;
    std::vector<Eigen::Vector3f> positions;
  };
  const std::vector<Level>& levels() const { return levels_; }  // coarsest first
  // Downsampling factor of each level from the input, coarsest first.
  static std::vector<int> factors(int width, const OdometryConfig& config);
  double timestamp() const { return timestamp_; }

 private:
  std::vector<Level> levels_;
  double timestamp_ = 0;
};

struct OdometryResult {
  Eigen::Isometry3d T_cur_ref = Eigen::Isometry3d::Identity();  // reference camera -> current
  bool converged = false;
  std::string reason;  // why not (empty when converged)
  int iterations = 0;
  double overlap = 0;  // finest level: fraction of reference points seen with depth
  // Gauss-Newton information of the estimate at the finest level (se(3), left perturbation of
  // T_cur_ref, translation first), in the robust weighted residuals' units.
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  double intensity_scale = 0, depth_scale = 0;  // the t-distribution scales at the end
  // The depth residuals' spread at the final pose, robustly (1.4826 x their median magnitude,
  // in units of the sensor noise; 0 without depth terms). Unlike depth_scale it holds while up to
  // half the points are occluded (a person walking in front): the t-distribution's scale gives
  // way once about 1 / (t_dof + 1) of them are.
  double depth_spread = 0;
  // The colour gain I_cur / I_ref the finest level aligned with (estimate_brightness; else 1).
  double gain = 1;
};

// The depth weight for aligning `current`, taken while the camera turned at `current_rate`
// rad/s, against a reference taken at `reference_rate`: either frame's blur breaks brightness
// constancy, so the two rates count together (their hypotenuse).
double blur_aware_depth_weight(const OdometryConfig& config, const OdometryFrame& current, double current_rate,
                               double reference_rate);

// Aligns `current` to `reference` starting from `initial_T_cur_ref`. A bad alignment is reported
// in the result, never thrown; mismatched pyramids throw splat::Error.
// The camera's velocity [v, omega] (its own axes, per second) as each frame was taken, for the
// rolling shutter's correction (OdometryConfig::rolling_shutter); zero: none.
struct FrameMotion {
  Eigen::Matrix<double, 6, 1> reference = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 1> current = Eigen::Matrix<double, 6, 1>::Zero();
};
OdometryResult align_rgbd(const OdometryFrame& reference, const OdometryFrame& current,
                          const Eigen::Isometry3d& initial_T_cur_ref, const OdometryConfig& config,
                          const FrameMotion& motion = {});

}  // namespace tracking
