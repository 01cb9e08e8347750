#include "io/video_io.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include "io/file_error.h"

namespace app {

struct Mp4Writer::Encoder {
  cv::VideoWriter writer;
  cv::Mat bgr;
};

Mp4Writer::Mp4Writer(const std::filesystem::path& path, int width, int height, double fps)
    : encoder_(std::make_unique<Encoder>()), path_(path), width_(width), height_(height) {
  if (width < 2 || height < 2 || width % 2 != 0 || height % 2 != 0) {
    fail(path, "H.264 needs an even width and height, got " + std::to_string(width) + "x" + std::to_string(height));
  }
  if (!(fps > 0 && fps <= 240)) fail(path, "frame rate " + std::to_string(fps) + " is not in (0, 240]");
  const bool opened = encoder_->writer.open(path.string(), cv::CAP_FFMPEG, cv::VideoWriter::fourcc('a', 'v', 'c', '1'), fps,
                                            cv::Size(width, height));
  if (!opened) fail(path, "no H.264 encoder (OpenCV's FFmpeg backend with libx264) could open this file");
  encoder_->bgr.create(height, width, CV_8UC3);
}

Mp4Writer::~Mp4Writer() = default;

void Mp4Writer::add(std::span<const float> rgb) {
  const std::size_t pixels = static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
  if (rgb.size() != pixels * 3) {
    fail(path_, "frame of " + std::to_string(rgb.size()) + " values, expected " + std::to_string(pixels * 3));
  }
  for (int y = 0; y < height_; ++y) {
    auto* row = encoder_->bgr.ptr<unsigned char>(y);
    for (int x = 0; x < width_; ++x) {
      const float* p = &rgb[(static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)) * 3];
      for (int c = 0; c < 3; ++c) {
        row[x * 3 + (2 - c)] = static_cast<unsigned char>(std::lround(std::clamp(p[c], 0.f, 1.f) * 255.f));
      }
    }
  }
  encoder_->writer.write(encoder_->bgr);
  ++frames_;
}

void Mp4Writer::finish() {
  encoder_->writer.release();
  std::error_code ec;
  if (std::filesystem::file_size(path_, ec) == 0 || ec) fail(path_, "the encoder wrote nothing");
}

}  // namespace app
