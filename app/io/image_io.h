#pragma once
#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "splat/image.h"

namespace app {

// Readers check an image's header before allocating its pixels: 16384 a side and 64 Mpixels
// (192 MiB as 8-bit RGB) at most.
inline constexpr char kImageSizeLimit[] = "16384 a side and 67108864 pixels";
inline bool image_size_allowed(std::uint64_t width, std::uint64_t height) {
  return width <= 16384 && height <= 16384 && width * height <= (std::uint64_t(1) << 26);
}

// Writes [H, W, 3] colour as 8-bit RGB PNG: clamped to [0, 1], rounded, no colour-space change
// (3DGS colours are display values already). Atomic. Throws splat::Error on failure.
void write_png_rgb(const std::filesystem::path& path, int width, int height,
                   std::span<const float> rgb);

// Writes a 16-bit greyscale PNG (for example depth in millimetres or TUM's 1/5000 m). Atomic.
void write_png_gray16(const std::filesystem::path& path, const splat::Image16& image);
void write_png_gray8(const std::filesystem::path& path, const splat::Image8& image);

// Writes an 8-bit RGB PNG from 8-bit data (plots, screenshots). Atomic.
void write_png_rgb8(const std::filesystem::path& path, const splat::Image8& image);

// Reads an 8-bit PNG as RGB (grey and palette expanded, alpha dropped).
splat::Image8 read_png_rgb8(const std::filesystem::path& path);

// JPEG (libjpeg): read as 8-bit RGB; write 8-bit RGB at `quality` (1..100), atomically.
splat::Image8 read_jpeg_rgb8(const std::filesystem::path& path);
void write_jpeg_rgb8(const std::filesystem::path& path, const splat::Image8& image, int quality = 95);

// PNG or JPEG by extension.
splat::Image8 read_rgb8(const std::filesystem::path& path);
// The same from an encoded image in memory (PNG or JPEG by its first bytes); `where` names it in
// errors. Each also on its own.
splat::Image8 decode_rgb8(std::span<const std::uint8_t> bytes, const std::string& where);
splat::Image8 decode_png_rgb8(std::span<const std::uint8_t> bytes, const std::string& where);
splat::Image8 decode_jpeg_rgb8(std::span<const std::uint8_t> bytes, const std::string& where);

// Reads a single-channel 16-bit PNG (depth maps) exactly as stored.
splat::Image16 read_png_gray16(const std::filesystem::path& path);
// An 8 or 16-bit greyscale PNG of class ids (label images), widened to 16 bits.
splat::Image16 read_png_labels(const std::filesystem::path& path);

// A rendering in one EXR file as compositing tools expect it: R, G, B linear light (the sRGB
// transfer removed) premultiplied by A, as 16-bit floats, and Z (depth in metres, 0 where
// nothing was hit) as a 32-bit float. `rgb` is the render as displayed, composited over `background`; it is taken off
// again, and the colour under each pixel's alpha linearized (exact where one surface covers the
// pixel, an approximation along edges). Atomic.
void write_render_exr(const std::filesystem::path& path, int width, int height,
                      std::span<const float> rgb, std::span<const float> alpha,
                      std::span<const float> depth, const std::array<float, 3>& background = {0, 0, 0});

// The sRGB transfer undone: display value to linear light (values above 1 follow the same curve).
float srgb_to_linear(float v);
// The sRGB transfer: linear light to display value (its inverse).
float linear_to_srgb(float v);

struct ExrImage {
  int width = 0, height = 0;
  std::map<std::string, std::vector<float>> channels;  // each [H, W]
};
ExrImage read_exr(const std::filesystem::path& path);

}  // namespace app
