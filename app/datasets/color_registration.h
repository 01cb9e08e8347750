// Colour that is not registered to depth (7-Scenes, raw Kinect streams without the driver's
// registration): the colour camera looks from about where the depth camera does, but through its
// own focal length and principal point, so a pixel's colour and depth see different points (by 30
// pixels at the edges of a 640x480 Kinect frame). Tracking and mapping know one pinhole camera:
// the colour images are resampled into the depth camera's pixels as they load.
#pragma once
#include <memory>
#include <span>
#include <string>

#include "splat/camera.h"
#include "splat/rgbd_frame.h"

namespace app {

// The colour camera's pinhole intrinsics, in pixels of an image the depth image's size; it shares
// the depth camera's centre and axes (the 2.5 cm between a Kinect's lenses is left out: it shifts
// colour by under 2 pixels per metre of depth change at 585 px focal).
struct ColorCamera {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  // "fx,fy,cx,cy", as --color-camera takes it and summary.json records it.
  std::string text() const;
};

// What --color-camera asks for: "auto" (estimated from the frames, kept only where it clearly
// beats registered colour), "registered" (colour already in the depth camera's pixels: TUM, the
// generator, drivers that register), or the colour camera's "fx,fy,cx,cy". Throws splat::Error
// naming the text for anything else.
struct ColorCameraChoice {
  enum Kind { kAuto, kRegistered, kGiven } kind = kAuto;
  ColorCamera given;
};
ColorCameraChoice parse_color_camera(const std::string& text);
inline constexpr const char* kRegisteredColor = "registered";

// Resamples colour images of `color` into `depth`'s pixels (bilinear); a pixel whose ray falls
// outside the colour image has no colour and is marked ignored (splat::RgbdFrame::ignore = 1),
// so that neither tracking nor mapping reads its colour.
class ColorResampler {
 public:
  ColorResampler(const splat::Camera& depth, const ColorCamera& color);
  const ColorCamera& color_camera() const { return color_; }
  // What a run records ("input"."color_camera"): the colour camera's text, or kRegisteredColor
  // without a resampler.
  static std::string record(const ColorResampler* resampler) {
    return resampler ? resampler->color_.text() : kRegisteredColor;
  }
  // Throws splat::Error when the frame is not the depth camera's size.
  void apply(splat::RgbdFrame& frame) const;

 private:
  struct Maps;
  splat::Camera depth_;
  ColorCamera color_;
  std::shared_ptr<const Maps> maps_;
};

// The colour camera found by edge alignment: depth discontinuities are where colour changes too,
// so the intrinsics that put the most colour gradient on the depth edges of `frames` (all one
// camera) win, searched coarse to fine over focal ratios 0.8-1.25 and principal point shifts of 3%
// of the width.
struct ColorCameraEstimate {
  ColorCamera camera;
  // The edge score (mean colour gradient on the depth edges) of `camera` over that of registered
  // colour; registration is kept where it is at least kMinGain.
  double gain = 1;
  std::size_t edge_points = 0;  // depth-edge pixels scored
  bool register_color = false;  // whether to resample (gain and edge points are enough)
  static constexpr double kMinGain = 1.15;  // teddy and the generated sequences (registered) score
                                           // at most 1.02; 7-Scenes' raw colour 2.6
  static constexpr std::size_t kMinEdgePoints = 500;
};
ColorCameraEstimate estimate_color_camera(std::span<const splat::RgbdFrame> frames);

}  // namespace app
