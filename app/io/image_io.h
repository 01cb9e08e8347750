#pragma once
#include <filesystem>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "splat/image.h"

namespace app {

// Writes [H, W, 3] colour as 8-bit RGB PNG: clamped to [0, 1], rounded, no colour-space change
// (3DGS colours are display values already). Atomic. Throws splat::Error on failure.
void write_png_rgb(const std::filesystem::path& path, int width, int height,
                   std::span<const float> rgb);

// Writes a 16-bit greyscale PNG (for example depth in millimetres or TUM's 1/5000 m). Atomic.
void write_png_gray16(const std::filesystem::path& path, const splat::Image16& image);

// Writes an 8-bit RGB PNG from 8-bit data (plots, screenshots). Atomic.
void write_png_rgb8(const std::filesystem::path& path, const splat::Image8& image);

// Reads an 8-bit PNG as RGB (grey and palette expanded, alpha dropped).
splat::Image8 read_png_rgb8(const std::filesystem::path& path);

// JPEG (libjpeg): read as 8-bit RGB; write 8-bit RGB at `quality` (1..100), atomically.
splat::Image8 read_jpeg_rgb8(const std::filesystem::path& path);
void write_jpeg_rgb8(const std::filesystem::path& path, const splat::Image8& image, int quality = 95);

// PNG or JPEG by extension.
splat::Image8 read_rgb8(const std::filesystem::path& path);

// Reads a single-channel 16-bit PNG (depth maps) exactly as stored.
splat::Image16 read_png_gray16(const std::filesystem::path& path);

// A rendering in one EXR file: R, G, B, A and Z (depth in metres, 0 where nothing was hit),
// all 32-bit float. Atomic.
void write_render_exr(const std::filesystem::path& path, int width, int height,
                      std::span<const float> rgb, std::span<const float> alpha,
                      std::span<const float> depth);

struct ExrImage {
  int width = 0, height = 0;
  std::map<std::string, std::vector<float>> channels;  // each [H, W]
};
ExrImage read_exr(const std::filesystem::path& path);

}  // namespace app
