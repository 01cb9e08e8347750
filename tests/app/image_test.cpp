#include <Imath/half.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "datasets/ros_image_decode.h"
#include "io/image_io.h"
#include "io/video_io.h"
#include "support/expect_error.h"
#include "support/run_command.h"
#include "support/temp_dir.h"

namespace {

using gslam::test::TempDir;

TEST(ImageFormats, ExrKeepsColourAsHalfAndDepthExactly) {
  TempDir dir;
  const int w = 7, h = 5;
  std::vector<float> rgb(w * h * 3), alpha(w * h), depth(w * h);
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = 0.01f * static_cast<float>(i) - 0.3f;
  for (std::size_t i = 0; i < alpha.size(); ++i) {
    alpha[i] = static_cast<float>(i) / 40.f;
    depth[i] = 1.5f + 0.125f * static_cast<float>(i);
  }
  app::write_render_exr(dir / "r.exr", w, h, rgb, alpha, depth);
  const app::ExrImage img = app::read_exr(dir / "r.exr");
  ASSERT_EQ(img.width, w);
  ASSERT_EQ(img.height, h);
  // Colour is stored linear and premultiplied: the display value over alpha, linearized, times
  // alpha (nothing where alpha is 0), rounded to a half float, as alpha is; depth as it is.
  for (int c = 0; c < 3; ++c) {
    const auto& plane = img.channels.at(std::string(1, "RGB"[c]));
    for (int p = 0; p < w * h; ++p) {
      const float a = alpha[p];
      const float expected = a > 0 ? app::srgb_to_linear(std::max(rgb[p * 3 + c] / a, 0.f)) * a : 0.f;
      ASSERT_EQ(plane[p], float(half(expected))) << "channel " << c << " pixel " << p;
      ASSERT_NEAR(plane[p], expected, expected / 1024) << "channel " << c << " pixel " << p;  // 11 bits
    }
  }
  for (int p = 0; p < w * h; ++p) ASSERT_EQ(img.channels.at("A")[p], float(half(alpha[p]))) << "pixel " << p;
  EXPECT_EQ(img.channels.at("Z"), depth);
}

TEST(ImageFormats, PngClampsAndRoundsToEightBits) {
  TempDir dir;
  const std::vector<float> rgb = {-0.5f, 0.5f, 2.f, 0.2f, 1.f, NAN};
  app::write_png_rgb(dir / "a.png", 2, 1, rgb);
  const splat::Image8 back = app::read_png_rgb8(dir / "a.png");
  ASSERT_EQ(back.width, 2);
  const std::vector<uint8_t> expected = {0, 128, 255, 51, 255, 0};
  EXPECT_EQ(back.data, expected);
}

TEST(ImageFormats, SixteenBitPngRoundTrips) {
  TempDir dir;
  splat::Image16 depth(3, 2, 1);
  for (std::size_t i = 0; i < depth.data.size(); ++i) depth.data[i] = static_cast<uint16_t>(1000 * i + 7);
  app::write_png_gray16(dir / "d.png", depth);
  EXPECT_EQ(app::read_png_gray16(dir / "d.png").data, depth.data);
  GSLAM_EXPECT_ERROR(app::read_png_rgb8(dir / "missing.png"), "missing.png", "cannot open");
  gslam::test::write_text(dir / "bad.png", "\x89PNG\r\n\x1a\n garbage");
  GSLAM_EXPECT_ERROR(app::read_png_rgb8(dir / "bad.png"), "bad.png");
  app::write_png_rgb(dir / "rgb.png", 2, 1, std::vector<float>(6, 0.5f));
  GSLAM_EXPECT_ERROR(app::read_png_gray16(dir / "rgb.png"), "rgb.png", "16-bit greyscale");
}

// A PNG whose header claims 100000x100000 pixels (40 GB as RGB) in a few bytes: refused from
// the header, before the pixels are allocated.
TEST(ImageFormats, PngHeaderClaimingGigapixelsIsRefusedBeforeAllocating) {
  TempDir dir;
  auto be32 = [](uint32_t v) {
    return std::string{char(v >> 24), char((v >> 16) & 255), char((v >> 8) & 255), char(v & 255)};
  };
  // CRC-32 as PNG chunks use it (libpng checks it before reading the header's fields).
  auto crc = [](const std::string& bytes) {
    uint32_t c = 0xffffffffu;
    for (unsigned char b : bytes) {
      c ^= b;
      for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
    }
    return c ^ 0xffffffffu;
  };
  auto chunk = [&](const std::string& type, const std::string& data) {
    return be32(static_cast<uint32_t>(data.size())) + type + data + be32(crc(type + data));
  };
  const std::string ihdr = be32(100000) + be32(100000) + std::string{8, 2, 0, 0, 0};  // 8-bit RGB
  const std::string png = std::string("\x89PNG\r\n\x1a\n", 8) + chunk("IHDR", ihdr) + chunk("IDAT", std::string("\x78\x9c\x03\x00\x00\x00\x00\x01", 8)) + chunk("IEND", "");
  gslam::test::write_text(dir / "huge.png", png);
  GSLAM_EXPECT_ERROR(app::read_png_rgb8(dir / "huge.png"), "huge.png", "100000x100000", "at most 16384 a side");
}

// A JPEG whose frame header claims 60000x60000 pixels: refused from the header as well, and
// found by its extension in any case.
TEST(ImageFormats, JpegHeaderClaimingGigapixelsIsRefusedBeforeAllocating) {
  TempDir dir;
  app::write_jpeg_rgb8(dir / "small.jpg", splat::Image8(8, 8, 3, 100), 90);
  std::string jpeg = gslam::test::read_text(dir / "small.jpg");
  const std::size_t sof = jpeg.find(std::string("\xff\xc0", 2));  // baseline frame header
  ASSERT_NE(sof, std::string::npos);
  // Marker, length (2), precision (1), then height and width, big-endian.
  for (std::size_t k : {sof + 5, sof + 7}) jpeg[k] = char(0xea), jpeg[k + 1] = char(0x60);
  gslam::test::write_text(dir / "huge.JPEG", jpeg);
  GSLAM_EXPECT_ERROR(app::read_rgb8(dir / "huge.JPEG"), "huge.JPEG", "60000x60000", "at most 16384 a side");
  EXPECT_EQ(app::read_rgb8(dir / "small.jpg").width, 8);
}

// An encoded image in memory (a ROS CompressedImage) decodes to the pixels its file reads as,
// PNG or JPEG told apart by their first bytes; other or broken bytes are an error naming them.
TEST(ImageFormats, EncodedBytesInMemoryDecodeAsTheirFiles) {
  TempDir dir;
  splat::Image8 image(5, 3, 3);
  for (std::size_t i = 0; i < image.data.size(); ++i) image.data[i] = static_cast<uint8_t>(17 * i);
  app::write_png_rgb8(dir / "a.png", image);
  app::write_jpeg_rgb8(dir / "a.jpg", image, 90);
  auto bytes_of = [&](const std::string& name) {
    const std::string text = gslam::test::read_text(dir / name);
    return std::vector<uint8_t>(text.begin(), text.end());
  };
  const std::vector<uint8_t> png = bytes_of("a.png"), jpeg = bytes_of("a.jpg");
  EXPECT_EQ(app::decode_rgb8(png, "png bytes").data, image.data);
  EXPECT_EQ(app::decode_rgb8(jpeg, "jpeg bytes").data, app::read_jpeg_rgb8(dir / "a.jpg").data);
  app::RosImage message;
  message.compressed = true;
  message.encoding = "rgb8; png compressed bgr8";
  message.data = png;
  EXPECT_EQ(app::decode_colour(message, "bag.mcap: /camera/rgb message 3").data, image.data);
  message.data.resize(png.size() / 2);
  GSLAM_EXPECT_ERROR(app::decode_colour(message, "bag.mcap: /camera/rgb message 3"),
                     "bag.mcap: /camera/rgb message 3", "png compressed");
  GSLAM_EXPECT_ERROR(
      app::decode_rgb8(std::vector<uint8_t>{'G', 'I', 'F', '8', '9', 'a'}, "gif bytes"),
      "gif bytes", "neither PNG nor JPEG");
  GSLAM_EXPECT_ERROR(app::decode_rgb8(std::vector<uint8_t>{}, "no bytes"), "no bytes");
  GSLAM_EXPECT_ERROR(app::decode_jpeg_rgb8(std::span(jpeg).first(jpeg.size() / 3), "cut jpeg"),
                     "cut jpeg");
}

// ffmpeg failing (here: no folder to write into) is an error naming the file and ffmpeg's
// reason, whether it shows while frames are sent or at the end; the writer leaves no process.
TEST(VideoFormats, EncoderFailureIsAnErrorNamingTheFile) {
  if (!gslam::test::program_available("ffmpeg"))
    GTEST_SKIP() << "ffmpeg not found (apt-get install ffmpeg)";
  TempDir dir;
  const std::filesystem::path path = dir / "missing" / "video.mp4";
  GSLAM_EXPECT_ERROR(
      {
        app::Mp4Writer video(path, 64, 48, 30);
        for (int k = 0; k < 50; ++k) video.add(std::vector<float>(64 * 48 * 3, 0.5f));
        video.finish();
      },
      path.c_str(), "ffmpeg failed");
  EXPECT_FALSE(std::filesystem::exists(path));
}

}  // namespace
