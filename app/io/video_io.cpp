#include "io/video_io.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "io/file_error.h"
#include "process/child_process.h"

namespace app {

// Frames go to Debian's ffmpeg program as raw RGB through its standard input. Linking FFmpeg's
// libraries (or OpenCV's videoio on them) would load some 200 shared libraries, 0.3 s, in every
// gslam process, of which few ever write a video.
struct Mp4Writer::Encoder {
  PipedChild child;
  std::filesystem::path log;
  std::vector<std::uint8_t> bytes;  // one frame as 8-bit RGB
  bool running = false;

  // Closes ffmpeg's input and waits for it; a failure names the file and ffmpeg's last words.
  void end(const std::filesystem::path& path, bool stop) {
    if (!running) return;
    running = false;
    close(child.input);
    if (stop) kill(child.pid, SIGKILL);
    const int code = wait_for_child(child.pid);
    const std::string said = last_line(log);
    std::error_code ignored;
    std::filesystem::remove(log, ignored);
    if (!stop && code != 0)
      fail(path, "ffmpeg failed (exit " + std::to_string(code) + "): " + said);
  }
};

void Mp4Writer::require_encoder(const std::filesystem::path& path) {
  if (!program_on_path("ffmpeg"))
    fail(path, "writing an MP4 needs the ffmpeg program (apt-get install ffmpeg)");
}

Mp4Writer::Mp4Writer(const std::filesystem::path& path, int width, int height, double fps)
    : encoder_(std::make_unique<Encoder>()), path_(path) {
  if (width < 2 || height < 2 || width % 2 != 0 || height % 2 != 0) {
    fail(path, "H.264 needs an even width and height, got " + std::to_string(width) + "x" + std::to_string(height));
  }
  if (!(fps > 0 && fps <= 240)) fail(path, "frame rate " + std::to_string(fps) + " is not in (0, 240]");
  require_encoder(path);
  static std::atomic<int> videos{0};
  encoder_->log =
      std::filesystem::temp_directory_path() /
      ("gslam-ffmpeg-" + std::to_string(getpid()) + "-" + std::to_string(videos++) + ".log");
  char rate[32];
  std::snprintf(rate, sizeof(rate), "%.9g", fps);
  encoder_->child = start_piped({"ffmpeg",
                                 "-hide_banner",
                                 "-loglevel",
                                 "error",
                                 "-y",
                                 "-f",
                                 "rawvideo",
                                 "-pix_fmt",
                                 "rgb24",
                                 "-video_size",
                                 std::to_string(width) + "x" + std::to_string(height),
                                 "-framerate",
                                 rate,
                                 "-i",
                                 "pipe:0",
                                 "-c:v",
                                 "libx264",
                                 "-pix_fmt",
                                 "yuv420p",
                                 "-f",
                                 "mp4",
                                 path.string()},
                                encoder_->log);
  encoder_->running = true;
  encoder_->bytes.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3);
}

Mp4Writer::~Mp4Writer() {
  try {
    encoder_->end(path_, true);  // not finished: an error stopped the frames
  } catch (...) {
  }
}

void Mp4Writer::add(std::span<const float> rgb) {
  std::vector<std::uint8_t>& bytes = encoder_->bytes;
  if (rgb.size() != bytes.size()) {
    fail(path_, "frame of " + std::to_string(rgb.size()) + " values, expected " +
                    std::to_string(bytes.size()));
  }
  if (!encoder_->running) fail(path_, "video already finished");
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    bytes[i] = static_cast<std::uint8_t>(std::lround(std::clamp(rgb[i], 0.f, 1.f) * 255.f));
  }
  if (!write_to_child(encoder_->child, bytes)) {
    encoder_->end(path_, false);  // throws with ffmpeg's reason
    fail(path_, "ffmpeg stopped reading frames");
  }
  ++frames_;
}

void Mp4Writer::finish() {
  encoder_->end(path_, false);
  std::error_code ec;
  if (std::filesystem::file_size(path_, ec) == 0 || ec) fail(path_, "the encoder wrote nothing");
}

}  // namespace app
