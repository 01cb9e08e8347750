// H.264 video in an .mp4, encoded by Debian's ffmpeg program with libx264.
#pragma once
#include <filesystem>
#include <memory>
#include <span>

namespace app {

class Mp4Writer {
 public:
  // Throws splat::Error naming the file when the size is odd (H.264's 4:2:0 needs even sides)
  // or no H.264 encoder opens.
  Mp4Writer(const std::filesystem::path& path, int width, int height, double fps);
  // Throws splat::Error naming `path` if the encoder (the ffmpeg program) is not installed: for
  // a command to check before it renders anything.
  static void require_encoder(const std::filesystem::path& path);
  ~Mp4Writer();
  Mp4Writer(const Mp4Writer&) = delete;
  Mp4Writer& operator=(const Mp4Writer&) = delete;

  // One frame: [height, width, 3] display values in [0, 1].
  void add(std::span<const float> rgb);
  // Writes the trailer; the file is complete once this returns.
  void finish();
  std::size_t frames() const { return frames_; }

 private:
  struct Encoder;
  std::unique_ptr<Encoder> encoder_;
  std::filesystem::path path_;
  std::size_t frames_ = 0;
};

}  // namespace app
