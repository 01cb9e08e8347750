#include "datasets/ros_image_decode.h"

#include <cmath>
#include <cstring>

#include "io/image_io.h"
#include "splat/error.h"

namespace app {
namespace {

[[noreturn]] void fail_at(const std::string& where, const std::string& what) {
  throw splat::Error(where + ": " + what);
}

int bytes_per_pixel(const std::string& encoding) {
  if (encoding == "rgb8" || encoding == "bgr8" || encoding == "8UC3") return 3;
  if (encoding == "rgba8" || encoding == "bgra8" || encoding == "8UC4") return 4;
  if (encoding == "mono8" || encoding == "8UC1") return 1;
  if (encoding == "16UC1" || encoding == "mono16") return 2;
  if (encoding == "32FC1") return 4;
  return 0;
}

// Checks width, height and step against the data before any pixel is touched.
void check_layout(const RosImage& image, int pixel_bytes, const std::string& where) {
  if (!image_size_allowed(image.width, image.height) || image.width == 0 || image.height == 0) {
    fail_at(where, "image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                       ", expected 1 to " + kImageSizeLimit);
  }
  const std::uint64_t row = std::uint64_t(image.width) * std::uint64_t(pixel_bytes);
  if (image.step < row) {
    fail_at(where, "step " + std::to_string(image.step) + " is less than width " +
                       std::to_string(image.width) + " x " + std::to_string(pixel_bytes) +
                       " bytes (" + image.encoding + ")");
  }
  const std::uint64_t needed = std::uint64_t(image.step) * image.height;
  if (image.data.size() < needed) {
    fail_at(where, "image data has " + std::to_string(image.data.size()) +
                       " bytes, expected step x height = " + std::to_string(needed));
  }
}

std::string encodings_read() {
  return "colour rgb8, bgr8, rgba8, bgra8, mono8 or a PNG/JPEG CompressedImage; depth 16UC1 (mm) "
         "or 32FC1 (m)";
}

}  // namespace

bool is_colour_encoding(const RosImage& h) {
  if (h.compressed) return h.encoding.find("compressedDepth") == std::string::npos;
  const int b = bytes_per_pixel(h.encoding);
  return b > 0 && h.encoding != "16UC1" && h.encoding != "mono16" && h.encoding != "32FC1";
}

bool is_depth_encoding(const RosImage& h) {
  return !h.compressed &&
         (h.encoding == "16UC1" || h.encoding == "mono16" || h.encoding == "32FC1");
}

double default_depth_scale(const RosImage& h) { return h.encoding == "32FC1" ? 1.0 : 1000.0; }

splat::Image8 decode_colour(const RosImage& image, const std::string& where) {
  if (image.compressed) {
    if (image.data.size() > (std::size_t(1) << 30)) fail_at(where, "compressed image over 1 GiB");
    // PNG or JPEG, any of their layouts, as 8-bit RGB (the readers check the size first).
    return decode_rgb8(image.data, where + ": compressed image (format '" + image.encoding + "')");
  }
  if (!is_colour_encoding(image)) {
    fail_at(where, "colour encoding '" + image.encoding + "' is not one gslam reads (" +
                       encodings_read() + ")");
  }
  const int b = bytes_per_pixel(image.encoding);
  check_layout(image, b, where);
  const bool bgr = image.encoding == "bgr8" || image.encoding == "bgra8";
  splat::Image8 out(static_cast<int>(image.width), static_cast<int>(image.height), 3);
  for (std::uint32_t y = 0; y < image.height; ++y) {
    const std::uint8_t* row = image.data.data() + std::size_t(y) * image.step;
    for (std::uint32_t x = 0; x < image.width; ++x) {
      const std::uint8_t* p = row + std::size_t(x) * b;
      for (int c = 0; c < 3; ++c) {
        out.at(static_cast<int>(x), static_cast<int>(y), c) = b == 1 ? p[0] : p[bgr ? 2 - c : c];
      }
    }
  }
  return out;
}

std::vector<float> decode_depth(const RosImage& image, double depth_scale,
                                const std::string& where) {
  if (!is_depth_encoding(image)) {
    fail_at(where, "depth encoding '" +
                       (image.compressed ? "compressed " + image.encoding : image.encoding) +
                       "' is not one gslam reads (16UC1 in millimetres or 32FC1 in metres)");
  }
  const bool f32 = image.encoding == "32FC1";
  check_layout(image, f32 ? 4 : 2, where);
  // As Dataset::load reads a depth PNG: value * (1 / scale) in float.
  const float inv = static_cast<float>(1.0 / depth_scale);
  std::vector<float> out(std::size_t(image.width) * image.height);
  for (std::uint32_t y = 0; y < image.height; ++y) {
    const std::uint8_t* row = image.data.data() + std::size_t(y) * image.step;
    for (std::uint32_t x = 0; x < image.width; ++x) {
      float value = 0;
      if (f32) {
        std::uint32_t bits;
        std::memcpy(&bits, row + std::size_t(x) * 4, 4);
        if (image.big_endian) bits = __builtin_bswap32(bits);
        float v;
        std::memcpy(&v, &bits, 4);
        value = std::isfinite(v) && v > 0 ? v * inv : 0.f;
      } else {
        std::uint16_t v;
        std::memcpy(&v, row + std::size_t(x) * 2, 2);
        if (image.big_endian) v = static_cast<std::uint16_t>((v >> 8) | (v << 8));
        value = static_cast<float>(v) * inv;
      }
      out[std::size_t(y) * image.width + x] = value;
    }
  }
  return out;
}

splat::RgbdFrame rgbd_frame_from_ros(const RosImage& colour, const RosImage& depth, const splat::Camera& intrinsics,
                                     double depth_scale, const std::string& colour_where,
                                     const std::string& depth_where) {
  const splat::Image8 rgb = decode_colour(colour, colour_where);
  if (rgb.width != intrinsics.width || rgb.height != intrinsics.height) {
    throw splat::Error(colour_where + ": image is " + std::to_string(rgb.width) + "x" + std::to_string(rgb.height) +
                       ", expected " + std::to_string(intrinsics.width) + "x" + std::to_string(intrinsics.height));
  }
  if (depth.width != std::uint32_t(rgb.width) || depth.height != std::uint32_t(rgb.height)) {
    throw splat::Error(depth_where + ": depth is " + std::to_string(depth.width) + "x" + std::to_string(depth.height) +
                       ", colour is " + std::to_string(rgb.width) + "x" + std::to_string(rgb.height));
  }
  splat::RgbdFrame f;
  f.timestamp = colour.stamp;
  f.camera = intrinsics;
  f.rgb.resize(rgb.data.size());
  for (std::size_t k = 0; k < rgb.data.size(); ++k) f.rgb[k] = static_cast<float>(rgb.data[k]) / 255.f;
  f.depth = decode_depth(depth, depth_scale, depth_where);
  return f;
}

}  // namespace app
