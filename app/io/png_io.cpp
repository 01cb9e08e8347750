#include <png.h>

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <memory>

#include "io/atomic_file.h"
#include "io/file_error.h"
#include "io/image_io.h"
#include "io/image_source.h"
#include "splat/error.h"

namespace app {
namespace {

using File = ImageSource;

// libpng reports errors by longjmp; this keeps the message for the exception.
struct PngErrors {
  char message[256] = "malformed PNG";
};
void on_png_error(png_structp png, png_const_charp msg) {
  auto* errors = static_cast<PngErrors*>(png_get_error_ptr(png));
  std::snprintf(errors->message, sizeof(errors->message), "%s", msg);
  png_longjmp(png, 1);
}
void on_png_warning(png_structp, png_const_charp) {}

void write_png(const std::filesystem::path& path, int width, int height, int bit_depth,
               int color_type, int bytes_per_pixel, const unsigned char* data) {
  if (width < 1 || height < 1) fail(path, "cannot write an empty image");
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    File file(std::fopen(tmp.c_str(), "wb"));
    if (!file) fail(tmp, "cannot open for writing");
    PngErrors errors;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &errors, on_png_error, on_png_warning);
    png_infop info = png_create_info_struct(png);
    if (setjmp(png_jmpbuf(png))) {
      png_destroy_write_struct(&png, &info);
      fail(tmp, errors.message);
    }
    png_init_io(png, file.get());
    png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), bit_depth,
                 color_type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_compression_level(png, 3);  // fast: renders are written often
    png_write_info(png, info);
    if (bit_depth == 16) png_set_swap(png);  // our samples are little-endian; PNG is big
    const std::size_t row_bytes = static_cast<std::size_t>(width) * bytes_per_pixel;
    for (int y = 0; y < height; ++y) {
      png_write_row(png, const_cast<unsigned char*>(data + static_cast<std::size_t>(y) * row_bytes));
    }
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
  });
}

// Reads a PNG from `file` (named `path` in errors) after `configure` sets its transforms;
// configure returns an error message, or an empty string to go on. No C++ object is created
// between setjmp and the reads.
template <typename T>
splat::ImageT<T> read_png(File file, const std::filesystem::path& path, int channels,
                          std::string (*configure)(png_structp, png_infop)) {
  unsigned char signature[8];
  if (std::fread(signature, 1, 8, file.get()) != 8 || png_sig_cmp(signature, 0, 8) != 0) {
    fail(path, "not a PNG file");
  }
  PngErrors errors;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &errors, on_png_error, on_png_warning);
  png_infop info = png_create_info_struct(png);
  splat::ImageT<T> image;
  std::vector<png_bytep> rows;
  std::string problem;
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    fail(path, errors.message);
  }
  png_init_io(png, file.get());
  png_set_sig_bytes(png, 8);
  png_read_info(png, info);
  problem = configure(png, info);
  if (problem.empty()) {
    png_read_update_info(png, info);
    const int got = static_cast<int>(png_get_channels(png, info));
    if (got != channels) problem = "has " + std::to_string(got) + " channels, expected " + std::to_string(channels);
  }
  if (!problem.empty()) {
    png_destroy_read_struct(&png, &info, nullptr);
    fail(path, problem);
  }
  const png_uint_32 png_width = png_get_image_width(png, info), png_height = png_get_image_height(png, info);
  // The header is checked before the pixels are allocated.
  if (!image_size_allowed(png_width, png_height)) {
    png_destroy_read_struct(&png, &info, nullptr);
    fail(path, "header says " + std::to_string(png_width) + "x" + std::to_string(png_height) + ", expected at most " +
                   kImageSizeLimit);
  }
  const int width = static_cast<int>(png_width), height = static_cast<int>(png_height);
  image = splat::ImageT<T>(width, height, channels);
  rows.resize(static_cast<std::size_t>(height));
  for (int y = 0; y < height; ++y) {
    rows[static_cast<std::size_t>(y)] = reinterpret_cast<png_bytep>(&image.data[static_cast<std::size_t>(y) * width * channels]);
  }
  png_read_image(png, rows.data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return image;
}

// Any 8-bit PNG's transforms to RGB.
std::string to_rgb8(png_structp png, png_infop info) {
  const int type = png_get_color_type(png, info);
  if (png_get_bit_depth(png, info) == 16) png_set_strip_16(png);
  if (type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (type == PNG_COLOR_TYPE_GRAY || type == PNG_COLOR_TYPE_GRAY_ALPHA) {
    if (png_get_bit_depth(png, info) < 8) png_set_expand_gray_1_2_4_to_8(png);
    png_set_gray_to_rgb(png);
  }
  if (type & PNG_COLOR_MASK_ALPHA) png_set_strip_alpha(png);
  return std::string();
}

}  // namespace

void write_png_rgb(const std::filesystem::path& path, int width, int height, std::span<const float> rgb) {
  if (rgb.size() != static_cast<std::size_t>(width) * height * 3) {
    fail(path, "image has " + std::to_string(rgb.size()) + " values, expected " + std::to_string(width) + "x" + std::to_string(height) + "x3");
  }
  std::vector<unsigned char> bytes(rgb.size());
  for (std::size_t i = 0; i < rgb.size(); ++i) {
    const float v = std::isfinite(rgb[i]) ? std::clamp(rgb[i], 0.f, 1.f) : 0.f;
    bytes[i] = static_cast<unsigned char>(std::lround(v * 255.f));
  }
  write_png(path, width, height, 8, PNG_COLOR_TYPE_RGB, 3, bytes.data());
}

void write_png_rgb8(const std::filesystem::path& path, const splat::Image8& image) {
  if (image.channels != 3) fail(path, "expected a 3-channel image");
  write_png(path, image.width, image.height, 8, PNG_COLOR_TYPE_RGB, 3, image.data.data());
}

void write_png_gray16(const std::filesystem::path& path, const splat::Image16& image) {
  if (image.channels != 1) fail(path, "expected a 1-channel image");
  write_png(path, image.width, image.height, 16, PNG_COLOR_TYPE_GRAY, 2,
            reinterpret_cast<const unsigned char*>(image.data.data()));
}

void write_png_gray8(const std::filesystem::path& path, const splat::Image8& image) {
  if (image.channels != 1) fail(path, "expected a 1-channel image");
  write_png(path, image.width, image.height, 8, PNG_COLOR_TYPE_GRAY, 1, image.data.data());
}

splat::Image8 read_png_rgb8(const std::filesystem::path& path) {
  return read_png<uint8_t>(open_image_file(path), path, 3, to_rgb8);
}

splat::Image8 decode_png_rgb8(std::span<const std::uint8_t> bytes, const std::string& where) {
  return read_png<uint8_t>(open_image_bytes(bytes, where), where, 3, to_rgb8);
}

splat::Image16 read_png_gray16(const std::filesystem::path& path) {
  return read_png<uint16_t>(open_image_file(path), path, 1, [](png_structp png, png_infop info) {
    if (png_get_color_type(png, info) != PNG_COLOR_TYPE_GRAY || png_get_bit_depth(png, info) != 16) {
      return "expected a 16-bit greyscale PNG (depth map), got colour type " +
             std::to_string(png_get_color_type(png, info)) + " with " +
             std::to_string(png_get_bit_depth(png, info)) + " bits";
    }
    png_set_swap(png);  // PNG stores big-endian samples
    return std::string();
  });
}

splat::Image16 read_png_labels(const std::filesystem::path& path) {
  // The bit depth decides the reader: IHDR's bit depth and colour type follow the signature,
  // the chunk's length and name, the width and the height (bytes 24 and 25).
  unsigned char header[26] = {};
  {
    File file(std::fopen(path.c_str(), "rb"));
    if (!file) fail(path, "cannot open file");
    if (std::fread(header, 1, sizeof header, file.get()) != sizeof header || png_sig_cmp(header, 0, 8) != 0) {
      fail(path, "not a PNG file");
    }
  }
  if (header[24] == 16) return read_png_gray16(path);
  const splat::Image8 narrow =
      read_png<uint8_t>(open_image_file(path), path, 1, [](png_structp png, png_infop info) {
        if (png_get_color_type(png, info) != PNG_COLOR_TYPE_GRAY ||
            png_get_bit_depth(png, info) != 8) {
          return "expected an 8 or 16-bit greyscale PNG of class ids, got colour type " +
                 std::to_string(png_get_color_type(png, info)) + " with " +
                 std::to_string(png_get_bit_depth(png, info)) + " bits";
        }
        return std::string();
      });
  splat::Image16 wide(narrow.width, narrow.height, 1);
  std::copy(narrow.data.begin(), narrow.data.end(), wide.data.begin());
  return wide;
}

}  // namespace app
