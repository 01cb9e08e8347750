#include <jpeglib.h>

#include <algorithm>
#include <cctype>
#include <csetjmp>
#include <cstdio>
#include <memory>

#include "io/atomic_file.h"
#include "io/image_io.h"
#include "io/image_source.h"
#include "splat/error.h"

namespace app {
namespace {

// libjpeg reports errors through this handler; it longjmps back with the message kept.
struct JpegError {
  jpeg_error_mgr mgr;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX] = "malformed JPEG";
};
void on_error(j_common_ptr info) {
  auto* err = reinterpret_cast<JpegError*>(info->err);
  (*info->err->format_message)(info, err->message);
  std::longjmp(err->jump, 1);
}

// Reads a JPEG from `file` (named `path` in errors) as 8-bit RGB.
splat::Image8 read_jpeg(ImageSource file, const std::filesystem::path& path) {
  jpeg_decompress_struct info;
  JpegError err;
  info.err = jpeg_std_error(&err.mgr);
  err.mgr.error_exit = on_error;
  splat::Image8 image;
  if (setjmp(err.jump)) {
    jpeg_destroy_decompress(&info);
    throw splat::Error(path.string() + ": " + err.message);
  }
  jpeg_create_decompress(&info);
  jpeg_stdio_src(&info, file.get());
  jpeg_read_header(&info, TRUE);
  if (!image_size_allowed(info.image_width, info.image_height)) {
    const std::string size = std::to_string(info.image_width) + "x" + std::to_string(info.image_height);
    jpeg_destroy_decompress(&info);
    throw splat::Error(path.string() + ": header says " + size + ", expected at most " + kImageSizeLimit);
  }
  info.out_color_space = JCS_RGB;
  jpeg_start_decompress(&info);
  image = splat::Image8(static_cast<int>(info.output_width), static_cast<int>(info.output_height), 3);
  while (info.output_scanline < info.output_height) {
    JSAMPROW row = &image.data[static_cast<std::size_t>(info.output_scanline) * info.output_width * 3];
    jpeg_read_scanlines(&info, &row, 1);
  }
  jpeg_finish_decompress(&info);
  jpeg_destroy_decompress(&info);
  return image;
}

}  // namespace

splat::Image8 read_jpeg_rgb8(const std::filesystem::path& path) {
  return read_jpeg(open_image_file(path), path);
}

splat::Image8 decode_jpeg_rgb8(std::span<const std::uint8_t> bytes, const std::string& where) {
  return read_jpeg(open_image_bytes(bytes, where), where);
}

void write_jpeg_rgb8(const std::filesystem::path& path, const splat::Image8& image, int quality) {
  if (image.channels != 3 || image.width < 1 || image.height < 1) throw splat::Error(path.string() + ": expected a non-empty RGB image");
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    std::unique_ptr<std::FILE, FileCloser> file(std::fopen(tmp.c_str(), "wb"));
    if (!file) throw splat::Error(tmp.string() + ": cannot open for writing");
    jpeg_compress_struct info;
    JpegError err;
    info.err = jpeg_std_error(&err.mgr);
    err.mgr.error_exit = on_error;
    if (setjmp(err.jump)) {
      jpeg_destroy_compress(&info);
      throw splat::Error(tmp.string() + ": " + err.message);
    }
    jpeg_create_compress(&info);
    jpeg_stdio_dest(&info, file.get());
    info.image_width = static_cast<JDIMENSION>(image.width);
    info.image_height = static_cast<JDIMENSION>(image.height);
    info.input_components = 3;
    info.in_color_space = JCS_RGB;
    jpeg_set_defaults(&info);
    jpeg_set_quality(&info, quality, TRUE);
    jpeg_start_compress(&info, TRUE);
    while (info.next_scanline < info.image_height) {
      JSAMPROW row = const_cast<JSAMPROW>(&image.data[static_cast<std::size_t>(info.next_scanline) * image.width * 3]);
      jpeg_write_scanlines(&info, &row, 1);
    }
    jpeg_finish_compress(&info);
    jpeg_destroy_compress(&info);
  });
}

splat::Image8 read_rgb8(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".jpg" || ext == ".jpeg") return read_jpeg_rgb8(path);
  return read_png_rgb8(path);
}

splat::Image8 decode_rgb8(std::span<const std::uint8_t> bytes, const std::string& where) {
  static constexpr std::uint8_t kPng[4] = {0x89, 'P', 'N', 'G'}, kJpeg[3] = {0xFF, 0xD8, 0xFF};
  if (bytes.size() >= 4 && std::equal(kPng, kPng + 4, bytes.begin()))
    return decode_png_rgb8(bytes, where);
  if (bytes.size() >= 3 && std::equal(kJpeg, kJpeg + 3, bytes.begin()))
    return decode_jpeg_rgb8(bytes, where);
  throw splat::Error(where + ": image is neither PNG nor JPEG");
}

}  // namespace app
