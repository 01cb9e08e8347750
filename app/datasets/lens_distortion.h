// Lens distortion of a camera whose images are not rectified (TUM's fr1 and fr2 Kinects, most raw
// ROS camera drivers), and the resampling that turns its frames into pinhole frames: the
// rasterizer, tracking and mapping only know the pinhole model.
#pragma once
#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "splat/camera.h"
#include "splat/rgbd_frame.h"

namespace app {

// OpenCV's (and ROS's plumb_bob) radial-tangential model on normalized coordinates (x, y):
// r^2 = x^2 + y^2, x_d = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2), and y_d
// alike with p1 and p2 swapped.
struct LensDistortion {
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;
  bool any() const { return k1 != 0 || k2 != 0 || p1 != 0 || p2 != 0 || k3 != 0; }
  // "k1,k2,p1,p2,k3" as written into summary.json and intrinsics.txt's order.
  std::vector<double> coefficients() const { return {k1, k2, p1, p2, k3}; }
};

// 4 coefficients (k1 k2 p1 p2) or 5 (with k3), all finite and under 100 in size; throws
// splat::Error naming `what` otherwise.
LensDistortion lens_distortion_from(const std::vector<double>& coefficients,
                                    const std::string& what);

// The undistorted normalized coordinates of distorted ones (inverts the model iteratively, to
// 1e-12).
std::vector<Eigen::Vector2d> undistort_normalized(const LensDistortion& distortion,
                                                  const std::vector<Eigen::Vector2d>& distorted);

// The numbers of a camera's text ("fx,fy,cx,cy,...", intrinsics.txt), split at `separator` (' ':
// any white space), at most `cap` of them; an empty or unreadable item is NaN.
std::vector<double> parse_numbers(const std::string& text, char separator, std::size_t cap);

// "k1,k2,p1,p2[,k3]"; throws splat::Error naming the text.
LensDistortion parse_lens_distortion(const std::string& text);

// A ROS CameraInfo's distortion: plumb_bob (4 or 5 coefficients; rational_polynomial with its
// extra terms zero reads alike); coefficients all zero are none, whatever the model. Throws
// splat::Error naming `where` for another model (fisheye) or too few coefficients.
LensDistortion lens_distortion_from_ros(const std::string& model, const std::vector<double>& d,
                                        const std::string& where);

// Resamples frames of a camera with lens distortion into a pinhole camera of the same size whose
// every pixel sees inside the raw image (OpenCV's optimal new camera with alpha 0: no border
// without colour or depth, at the cost of a little of the view). Colour is interpolated
// bilinearly; depth too where the four raw pixels around are one surface, else it is the
// nearest raw pixel's, so that no depth is made up across an object's edge or a hole; labels and
// the ignore mask take the nearest raw pixel.
class Undistortion {
 public:
  // Throws splat::Error naming `where` when the distortion folds the image over (coefficients
  // no lens has) or leaves no usable view.
  Undistortion(const splat::Camera& raw, const LensDistortion& distortion,
               const std::string& where);
  // The pinhole camera that frames come out in, and the raw one they come in.
  const splat::Camera& camera() const { return pinhole_; }
  const splat::Camera& raw_camera() const { return raw_; }
  const LensDistortion& distortion() const { return distortion_; }
  // The frame in camera(): its raw images must be raw.width x raw.height.
  void apply(splat::RgbdFrame& frame) const;

 private:
  struct Maps;
  splat::Camera raw_, pinhole_;
  LensDistortion distortion_;
  std::shared_ptr<const Maps> maps_;
};

}  // namespace app
