// Frames: PNG (8-bit colour, 16-bit depth) and JPEG (io/image_io.h).
#include "fuzz_input.h"
#include "io/image_io.h"
#include "splat/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::filesystem::path png = gslam::fuzz::write_input("frame.png", data, size);
  const std::filesystem::path jpg = gslam::fuzz::write_input("frame.jpg", data, size);
  try { app::read_png_rgb8(png); } catch (const splat::Error&) {}
  try { app::read_png_gray16(png); } catch (const splat::Error&) {}
  try { app::read_jpeg_rgb8(jpg); } catch (const splat::Error&) {}
  try {
    app::decode_rgb8({data, size}, "frame");
  } catch (const splat::Error&) {
  }  // a ROS CompressedImage
  return 0;
}
