#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>

#include <gtest/gtest.h>

#include "io/ply_io.h"
#include "support/expect_error.h"
#include "support/random_scene.h"
#include "support/temp_dir.h"
#include "support/test_data.h"

namespace {

using gslam::test::TempDir;
using gslam::test::write_text;

splat::Gaussians sample_map(int sh_degree, int count = 20) {
  gslam::test::SceneOptions o;
  o.sh_degree = sh_degree;
  o.count = count;
  return gslam::test::make_random_scene<float>(o).gaussians;
}

void expect_bit_identical(const splat::Gaussians& a, const splat::Gaussians& b) {
  ASSERT_EQ(a.sh_degree, b.sh_degree);
  for (splat::ParamGroup group : splat::kAllParamGroups) {
    const auto& x = splat::param_group(a, group);
    const auto& y = splat::param_group(b, group);
    ASSERT_EQ(x.size(), y.size()) << splat::param_group_name(group);
    EXPECT_EQ(std::memcmp(x.data(), y.data(), x.size() * sizeof(float)), 0) << splat::param_group_name(group);
  }
}

TEST(PlyFormat, RoundTripIsBitExactForEveryShDegree) {
  TempDir dir;
  for (int degree = 0; degree <= 3; ++degree) {
    const splat::Gaussians map = sample_map(degree);
    app::write_ply(dir / "map.ply", map);
    const app::PlyMap back = app::read_ply(dir / "map.ply");
    expect_bit_identical(map, back.gaussians);
    EXPECT_TRUE(back.skipped_properties.empty());
  }
}

// A semantic map's classes (label_k, label_probability_k) come back as written, beside the
// Gaussians; a file naming one without the other is refused.
TEST(PlyFormat, LabelsRoundTrip) {
  TempDir dir;
  const splat::Gaussians map = sample_map(1, 5);
  splat::GaussianLabels labels;
  labels.top = 2;
  labels.ids = {1, 7, 3, 0, 65535, 2, 0, 0, 4, 1};
  labels.probabilities = {0.75f, 0.25f, 1.f, 0.f, 0.5f, 0.5f, 0.f, 0.f, 0.9f, 0.1f};
  app::write_ply(dir / "map.ply", map, &labels);
  const app::PlyMap back = app::read_ply(dir / "map.ply");
  expect_bit_identical(map, back.gaussians);
  EXPECT_EQ(back.labels.top, 2);
  EXPECT_EQ(back.labels.ids, labels.ids);
  EXPECT_EQ(back.labels.probabilities, labels.probabilities);
  EXPECT_TRUE(back.skipped_properties.empty());
  app::write_ply(dir / "plain.ply", map);
  EXPECT_TRUE(app::read_ply(dir / "plain.ply").labels.empty());

  write_text(dir / "half.ply",
             "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
             "property float f_dc_0\nproperty float f_dc_1\nproperty float f_dc_2\nproperty float opacity\n"
             "property float scale_0\nproperty float scale_1\nproperty float scale_2\nproperty float rot_0\n"
             "property float rot_1\nproperty float rot_2\nproperty float rot_3\nproperty ushort label_0\nend_header\n"
             "0 0 0 0 0 0 0 0 0 0 1 0 0 0 3\n");
  EXPECT_THROW(app::read_ply(dir / "half.ply"), splat::Error);
}

TEST(PlyFormat, ReadsAsciiAndBigEndian) {
  TempDir dir;
  const std::string props =
      "property float x\nproperty float y\nproperty float z\nproperty float f_dc_0\nproperty float f_dc_1\n"
      "property float f_dc_2\nproperty float opacity\nproperty float scale_0\nproperty float scale_1\n"
      "property float scale_2\nproperty float rot_0\nproperty float rot_1\nproperty float rot_2\nproperty float rot_3\n";
  write_text(dir / "a.ply", "ply\nformat ascii 1.0\nelement vertex 1\n" + props +
                                "end_header\n1 2 3 0.1 0.2 0.3 0.5 -1 -2 -3 1 0 0 0\n");
  const auto ascii = app::read_ply(dir / "a.ply").gaussians;
  ASSERT_EQ(ascii.size(), 1u);
  EXPECT_FLOAT_EQ(ascii.means[2], 3.f);
  EXPECT_FLOAT_EQ(ascii.sh[1], 0.2f);
  EXPECT_FLOAT_EQ(ascii.log_scales[2], -3.f);

  std::string big = "ply\nformat binary_big_endian 1.0\nelement vertex 1\n" + props + "end_header\n";
  const float values[14] = {1, 2, 3, 0.1f, 0.2f, 0.3f, 0.5f, -1, -2, -3, 1, 0, 0, 0};
  for (float v : values) {
    char b[4];
    std::memcpy(b, &v, 4);
    big += std::string{b[3], b[2], b[1], b[0]};
  }
  write_text(dir / "b.ply", big);
  expect_bit_identical(ascii, app::read_ply(dir / "b.ply").gaussians);
}

TEST(PlyFormat, LoadsRealDonutMapWithShDegreeZeroAndNoNormals) {
  GSLAM_REQUIRE_SHARED_DATA(path, "v3dg_donut_3dgs_ply/fused.ply");
  const app::PlyMap map = app::read_ply(path);
  EXPECT_EQ(map.gaussians.size(), 45624u);
  EXPECT_EQ(map.gaussians.sh_degree, 0);
  EXPECT_TRUE(map.skipped_properties.empty());
  TempDir dir;
  app::write_ply(dir / "donut.ply", map.gaussians);
  expect_bit_identical(map.gaussians, app::read_ply(dir / "donut.ply").gaussians);
}

TEST(PlyFormat, LoadsRealShDegreeThreeMapAndSkipsExtraProperty) {
  GSLAM_REQUIRE_SHARED_DATA(path, "supersplat_fruit_drops_3dgs_ply/fruit_drops_minimal.ply");
  const app::PlyMap map = app::read_ply(path);
  EXPECT_EQ(map.gaussians.size(), 4721u);
  EXPECT_EQ(map.gaussians.sh_degree, 3);
  ASSERT_EQ(map.skipped_properties, std::vector<std::string>{"transform"});
  // f_rest is channel-major: f_rest_0 is coefficient 1 of red, f_rest_15 coefficient 1 of green.
  int nonzero = 0;
  for (std::size_t i = 0; i < map.gaussians.size(); ++i) nonzero += map.gaussians.sh[i * 48 + 3 * 5 + 1] != 0;
  EXPECT_GT(nonzero, 4000) << "view-dependent SH should be populated";
}

TEST(PlyFormat, BadInputGivesErrorNamingFileAndElement) {
  TempDir dir;
  GSLAM_EXPECT_ERROR(app::read_ply(dir / "missing.ply"), "missing.ply", "cannot open");
  write_text(dir / "text.ply", "hello\n");
  GSLAM_EXPECT_ERROR(app::read_ply(dir / "text.ply"), "text.ply", "not a PLY file");
  write_text(dir / "noend.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 3\n");
  GSLAM_EXPECT_ERROR(app::read_ply(dir / "noend.ply"), "no end_header");

  app::write_ply(dir / "good.ply", sample_map(1, 5));
  std::ifstream in(dir / "good.ply", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  write_text(dir / "truncated.ply", bytes.substr(0, bytes.size() - 10));
  GSLAM_EXPECT_ERROR(app::read_ply(dir / "truncated.ply"), "truncated.ply", "truncated", "'vertex' declares 5 entries");

  const std::string header = "ply\nformat ascii 1.0\nelement vertex 1\n";
  const std::string tail =
      "property float y\nproperty float z\nproperty float f_dc_0\nproperty float f_dc_1\n"
      "property float f_dc_2\nproperty float opacity\nproperty float scale_0\nproperty float scale_1\n"
      "property float scale_2\nproperty float rot_0\nproperty float rot_1\nproperty float rot_2\n"
      "property float rot_3\nend_header\n";
  write_text(dir / "type.ply", header + "property uchar x\n" + tail + "1 2 3 0 0 0 0 0 0 0 1 0 0 0\n");
  GSLAM_EXPECT_ERROR(app::read_ply(dir / "type.ply"), "property 'x' has type uchar, expected float");
  write_text(dir / "nan.ply", header + "property float x\n" + tail + "1 2 3 0 0 0 nan 0 0 0 1 0 0 0\n");
  GSLAM_EXPECT_ERROR(app::read_ply(dir / "nan.ply"), "nan.ply", "vertex 0 property 'opacity'", "finite");
  write_text(dir / "missing_prop.ply", header + tail + "2 3 0 0 0 0 0 0 0 1 0 0 0\n");
  GSLAM_EXPECT_ERROR(app::read_ply(dir / "missing_prop.ply"), "vertex property 'x' is missing");
  write_text(dir / "short.ply", header + "property float x\n" + tail + "1 2 3" + std::string(40, ' ') + "\n");
  GSLAM_EXPECT_ERROR(app::read_ply(dir / "short.ply"), "vertex 0 has 3 values, expected 14");
  write_text(dir / "rest.ply", header + "property float x\nproperty float f_rest_0\n" + tail +
                                   "1 2 3 4 0 0 0 0 0 0 0 1 0 0 0\n");
  GSLAM_EXPECT_ERROR(app::read_ply(dir / "rest.ply"), "1 f_rest properties", "SH degree");
}

// Hostile headers: each is refused from the header and the file's size, before anything is
// allocated or read (a 3.8 KB file once asked for 5.5 GB; junk elements looped past the end).
TEST(PlyFormat, HostileHeadersAreRefusedBeforeAllocating) {
  TempDir dir;
  const std::string props =
      "property float x\nproperty float y\nproperty float z\nproperty float f_dc_0\nproperty float f_dc_1\n"
      "property float f_dc_2\nproperty float opacity\nproperty float scale_0\nproperty float scale_1\n"
      "property float scale_2\nproperty float rot_0\nproperty float rot_1\nproperty float rot_2\n"
      "property float rot_3\nend_header\n";
  write_text(dir / "bomb.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 100000000\n" + props + std::string(3800, 'x'));
  GSLAM_EXPECT_ERROR(app::read_ply(dir / "bomb.ply"), "bomb.ply", "'vertex' declares 100000000 entries", "3800 bytes");
  write_text(dir / "junk.ply", "ply\nformat ascii 1.0\nelement junk 1000000000000\nproperty float a\nelement vertex 1\n" + props +
                                   "0 0 0 0 0 0 0 0 0 0 1 0 0 0\n");
  GSLAM_EXPECT_ERROR(app::read_ply(dir / "junk.ply"), "junk.ply", "'junk' declares 1000000000000 entries");
  write_text(dir / "overflow.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 18446744073709551615\n" + props);
  GSLAM_EXPECT_ERROR(app::read_ply(dir / "overflow.ply"), "overflow.ply", "'vertex' declares 18446744073709551615 entries");
  write_text(dir / "exp.ply", "ply\nformat ascii 1.0\nelement vertex 1e3\n" + props);
  GSLAM_EXPECT_ERROR(app::read_ply(dir / "exp.ply"), "exp.ply", "header line 3", "count '1e3' is not a non-negative integer");
  write_text(dir / "neg.ply", "ply\nformat ascii 1.0\nelement vertex -1\n" + props);
  GSLAM_EXPECT_ERROR(app::read_ply(dir / "neg.ply"), "count '-1' is not a non-negative integer");
}

}  // namespace
