#include <Imath/half.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfThreading.h>

#include <algorithm>
#include <cmath>
#include <thread>
#include <vector>

#include "io/atomic_file.h"
#include "io/image_io.h"
#include "splat/error.h"

namespace app {

float srgb_to_linear(float v) {
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

float linear_to_srgb(float v) {
  return v <= 0.0031308f ? v * 12.92f : 1.055f * std::pow(v, 1 / 2.4f) - 0.055f;
}

void write_render_exr(const std::filesystem::path& path, int width, int height,
                      std::span<const float> display_rgb, std::span<const float> alpha,
                      std::span<const float> depth, const std::array<float, 3>& background) {
  const std::size_t pixels = static_cast<std::size_t>(width) * height;
  if (width < 1 || height < 1 || display_rgb.size() != pixels * 3 || alpha.size() != pixels || depth.size() != pixels) {
    throw splat::Error(path.string() + ": EXR planes do not match " + std::to_string(width) + "x" + std::to_string(height));
  }
  // Premultiplied linear: the background taken off, the covered colour linearized, times alpha.
  // Colour and alpha as half floats (as renders usually are; float rendered noise does not
  // compress, so float planes took six times the disk and most of a run's output time), depth
  // as float.
  std::vector<half> rgba(pixels * 4, half(0.f));
  for (std::size_t p = 0; p < pixels; ++p) {
    const float a = alpha[p];
    rgba[p * 4 + 3] = half(a);
    if (!(a > 0)) continue;
    for (int c = 0; c < 3; ++c) {
      const float covered = (display_rgb[p * 3 + c] - (1 - a) * background[static_cast<std::size_t>(c)]) / a;
      rgba[p * 4 + c] = half(srgb_to_linear(std::max(covered, 0.f)) * a);
    }
  }
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    try {
      Imf::Header header(width, height);
      header.compression() = Imf::ZIP_COMPRESSION;
      header.zipCompressionLevel() = 1;  // level 6 took half again as long for 2% less
      Imf::FrameBuffer fb;
      char* base = reinterpret_cast<char*>(rgba.data());
      for (int c = 0; c < 4; ++c) {
        const std::string name(1, "RGBA"[c]);
        header.channels().insert(name, Imf::Channel(Imf::HALF));
        fb.insert(name, Imf::Slice(Imf::HALF, base + c * sizeof(half), 4 * sizeof(half), 4 * sizeof(half) * width));
      }
      header.channels().insert("Z", Imf::Channel(Imf::FLOAT));
      fb.insert("Z", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(depth.data())), sizeof(float), sizeof(float) * width));
      // Compressing is most of the time: its blocks of lines go to every core.
      static const int threads = [] {
        const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
        Imf::setGlobalThreadCount(cores);
        return cores;
      }();
      Imf::OutputFile file(tmp.c_str(), header, threads);
      file.setFrameBuffer(fb);
      file.writePixels(height);
    } catch (const std::exception& e) {
      throw splat::Error(tmp.string() + ": cannot write EXR: " + e.what());
    }
  });
}

ExrImage read_exr(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path)) throw splat::Error(path.string() + ": cannot open file");
  try {
    Imf::InputFile file(path.c_str());
    const Imath::Box2i window = file.header().dataWindow();
    ExrImage image;
    image.width = window.max.x - window.min.x + 1;
    image.height = window.max.y - window.min.y + 1;
    Imf::FrameBuffer fb;
    for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it) {
      auto& plane = image.channels[it.name()];
      plane.assign(static_cast<std::size_t>(image.width) * image.height, 0.f);
      char* origin = reinterpret_cast<char*>(plane.data()) -
                     (static_cast<std::ptrdiff_t>(window.min.y) * image.width + window.min.x) * static_cast<std::ptrdiff_t>(sizeof(float));
      fb.insert(it.name(), Imf::Slice(Imf::FLOAT, origin, sizeof(float), sizeof(float) * static_cast<std::size_t>(image.width)));
    }
    file.setFrameBuffer(fb);
    file.readPixels(window.min.y, window.max.y);
    return image;
  } catch (const std::exception& e) {
    throw splat::Error(path.string() + ": cannot read EXR: " + e.what());
  }
}

}  // namespace app
