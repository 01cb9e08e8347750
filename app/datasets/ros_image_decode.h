// Pixels of ROS image messages as gslam takes them: colour as 8-bit RGB, depth in metres.
#pragma once
#include <string>
#include <vector>

#include "datasets/bag_reader.h"
#include "splat/image.h"
#include "splat/rgbd_frame.h"

namespace app {

// Encodings gslam reads: colour Image rgb8, bgr8, rgba8, bgra8, mono8, or a CompressedImage
// (PNG or JPEG); depth Image 16UC1 (mono16, millimetres by ROS convention) or 32FC1 (metres).
bool is_colour_encoding(const RosImage& header);
bool is_depth_encoding(const RosImage& header);
// Depth values per metre by the ROS convention of the encoding: 16UC1 1000, 32FC1 1.
double default_depth_scale(const RosImage& header);

// The image as [H, W, 3] 8-bit RGB. Throws splat::Error starting with `where` (file and topic)
// for another encoding, a data size that does not match width, height and step, a size over
// image_size_allowed, or a compressed image that does not decode.
splat::Image8 decode_colour(const RosImage& image, const std::string& where);

// Depth [H, W] in metres: each stored value times float(1 / depth_scale), exactly as a depth PNG
// is read, so that the same values give the same floats. Not finite or negative: 0 (no depth).
// Throws splat::Error starting with `where` as decode_colour does.
std::vector<float> decode_depth(const RosImage& image, double depth_scale,
                                const std::string& where);

// The frame a colour and a depth message make, for the camera `intrinsics` (whose size both
// must have). Throws splat::Error starting with `colour_where` or `depth_where` as above, or
// for a size that differs from the camera's or the other image's.
splat::RgbdFrame rgbd_frame_from_ros(const RosImage& colour, const RosImage& depth, const splat::Camera& intrinsics,
                                     double depth_scale, const std::string& colour_where,
                                     const std::string& depth_where);

}  // namespace app
