#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>

#include <gtest/gtest.h>

#include <tiny_gltf.h>

#include "io/gltf_io.h"
#include "io/image_io.h"
#include "support/expect_error.h"
#include "support/random_scene.h"
#include "support/temp_dir.h"
#include "support/test_data.h"

namespace {

using gslam::test::TempDir;

TEST(GltfFormat, RoundTripWithinFloatPrecision) {
  TempDir dir;
  for (const char* name : {"map.glb", "map.gltf"}) {
    gslam::test::SceneOptions o;
    o.sh_degree = 3;
    o.count = 30;
    const splat::Gaussians map = gslam::test::make_random_scene<float>(o).gaussians;
    app::write_gltf(dir / name, map);
    const app::GltfSplatScene scene = app::read_gltf_splats(dir / name);
    ASSERT_EQ(scene.primitives.size(), 1u);
    EXPECT_EQ(scene.primitives[0].kernel, "ellipse");
    EXPECT_TRUE(scene.notices.empty());
    const splat::Gaussians back = app::to_gaussians(scene);
    ASSERT_EQ(back.size(), map.size());
    ASSERT_EQ(back.sh_degree, 3);
    EXPECT_EQ(back.means, map.means) << name;
    // SCALE is stored linear: exp, then log on reading.
    ASSERT_EQ(back.log_scales.size(), map.log_scales.size());
    for (std::size_t i = 0; i < map.log_scales.size(); ++i) EXPECT_NEAR(back.log_scales[i], map.log_scales[i], 1e-6f) << i;
    EXPECT_EQ(back.sh, map.sh) << name;
    for (std::size_t i = 0; i < map.size(); ++i) {
      // Rotations are stored normalized; compare the unit quaternions.
      const float* q = &map.rotations[i * 4];
      const float norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
      for (int k = 0; k < 4; ++k) EXPECT_NEAR(back.rotations[i * 4 + k], q[k] / norm, 1e-6f) << "splat " << i;
      // Opacity is stored after the sigmoid; compare in that space.
      auto sigmoid = [](float x) { return 1 / (1 + std::exp(-x)); };
      EXPECT_NEAR(sigmoid(back.opacity_logits[i]), sigmoid(map.opacity_logits[i]), 1e-6f) << "splat " << i;
    }
  }
}

// A semantic map's classes travel as _LABEL_k / _LABEL_PROBABILITY_k and read back exactly; a
// file without them has none, and malformed ones are one-line errors.
TEST(GltfFormat, LabelsRoundTrip) {
  TempDir dir;
  gslam::test::SceneOptions o;
  o.count = 5;
  const splat::Gaussians map = gslam::test::make_random_scene<float>(o).gaussians;
  splat::GaussianLabels labels;
  labels.top = 2;
  labels.ids = {1, 7, 3, 0, 65535, 2, 0, 0, 4, 1};
  labels.probabilities = {0.75f, 0.25f, 1.f, 0.f, 0.5f, 0.5f, 0.f, 0.f, 0.9f, 0.1f};
  app::write_gltf(dir / "labelled.glb", map, Eigen::Quaterniond::Identity(), &labels);
  const app::GltfSplatScene scene = app::read_gltf_splats(dir / "labelled.glb");
  const splat::GaussianLabels back = app::to_labels(scene);
  EXPECT_EQ(back.top, 2);
  EXPECT_EQ(back.ids, labels.ids);
  EXPECT_EQ(back.probabilities, labels.probabilities);
  EXPECT_TRUE(scene.notices.empty());
  app::write_gltf(dir / "plain.glb", map);
  EXPECT_TRUE(app::to_labels(app::read_gltf_splats(dir / "plain.glb")).empty());
  splat::GaussianLabels short_labels = labels;
  short_labels.ids.resize(4);
  short_labels.probabilities.resize(4);
  GSLAM_EXPECT_ERROR(app::write_gltf(dir / "bad.glb", map, Eigen::Quaterniond::Identity(), &short_labels),
                     "labels for 2 Gaussians, the map has 5");
  labels.probabilities[3] = 1.5f;  // not a probability
  app::write_gltf(dir / "odd.glb", map, Eigen::Quaterniond::Identity(), &labels);
  GSLAM_EXPECT_ERROR(app::read_gltf_splats(dir / "odd.glb"), "odd.glb", "Gaussian 1: _LABEL_1 0.000000, _LABEL_PROBABILITY_1 1.500000");
}

// Expected values from the fixtures' SOURCE.md (bevy_gaussian_splatting's conformance test).
TEST(GltfFormat, DecodesEveryConformanceFixtureCase) {
  for (const char* file : {"khr_conformance_matrix.gltf", "khr_conformance_matrix.glb"}) {
    GSLAM_REQUIRE_SHARED_DATA(path, std::string("khr_gaussian_splatting_fixtures_bevy/") + file);
    const app::GltfSplatScene scene = app::read_gltf_splats(path);
    std::map<std::string, const app::GltfSplatPrimitive*> by_name;
    for (const auto& p : scene.primitives) by_name[p.name] = &p;
    ASSERT_EQ(by_name.size(), 15u) << file;
    const std::map<std::string, std::vector<float>> scales = {
        {"scale_f32", {0.2f, -0.1f, 0.7f}},  {"scale_i8", {1, -2, 3}},      {"scale_i8_norm", {1, 0, -1}},
        {"scale_i16", {2, -3, 4}},           {"scale_i16_norm", {1, 0, -1}}, {"rotation_f32", {0, 0.5f, -0.5f}},
        {"opacity_f32", {0, 0.5f, -0.5f}}};
    for (const auto& [name, expected] : scales) {
      ASSERT_TRUE(by_name.count(name)) << name;
      for (int a = 0; a < 3; ++a) EXPECT_NEAR(by_name[name]->log_scales[a], expected[a], 1e-6f) << file << " " << name;
    }
    const std::map<std::string, float> opacities = {{"opacity_f32", 0.75f},
                                                    {"opacity_u8_norm", 64.f / 255.f},
                                                    {"opacity_u16_norm", 16384.f / 65535.f},
                                                    {"scale_f32", 0.25f}};
    for (const auto& [name, expected] : opacities) {
      EXPECT_NEAR(by_name[name]->opacities[0], expected, 1e-7f) << file << " " << name;
    }
    EXPECT_EQ(by_name["scale_f32"]->color_space, "srgb_rec709_display");
    EXPECT_EQ(by_name["rotation_f32"]->color_space, "lin_rec709_display");
    for (int degree = 0; degree <= 3; ++degree) {
      const auto* p = by_name["sh_degree" + std::to_string(degree)];
      EXPECT_EQ(p->sh_degree, degree) << file;
      EXPECT_EQ(p->sh.size(), static_cast<std::size_t>(3 * (degree + 1) * (degree + 1))) << file;
    }
    // Normalized integer rotations decode to (near) unit quaternions.
    for (const char* name : {"rotation_i8_norm", "rotation_i16_norm"}) {
      const auto& q = by_name[name]->rotations_xyzw;
      EXPECT_NEAR(std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]), 1.f, 0.02f) << name;
    }
    EXPECT_EQ(app::to_gaussians(scene).size(), 15u);
  }
}

TEST(GltfFormat, UnknownKernelAndColourSpaceFallBackWithNotices) {
  GSLAM_REQUIRE_SHARED_DATA(path, "khr_gaussian_splatting_fixtures_bevy/khr_extensible_fallback.gltf");
  const app::GltfSplatScene scene = app::read_gltf_splats(path);
  ASSERT_EQ(scene.primitives.size(), 1u);
  EXPECT_EQ(scene.primitives[0].kernel, "customShape");
  EXPECT_TRUE(scene.primitives[0].sh_from_color0);
  EXPECT_EQ(scene.notices.size(), 3u);  // COLOR_0 fallback, kernel, colour space
  const splat::Gaussians g = app::to_gaussians(scene);
  ASSERT_EQ(g.size(), 1u);
  EXPECT_FLOAT_EQ(g.means[0], 1.f);
  EXPECT_FLOAT_EQ(g.means[2], 3.f);
}

TEST(GltfFormat, BadInputGivesErrorNamingFileAndElement) {
  TempDir dir;
  GSLAM_EXPECT_ERROR(app::read_gltf_splats(dir / "missing.glb"), "missing.glb", "cannot open");
  gslam::test::write_text(dir / "broken.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [");
  GSLAM_EXPECT_ERROR(app::read_gltf_splats(dir / "broken.gltf"), "broken.gltf");
  gslam::test::write_text(dir / "garbage.glb", "glTF this is not a binary glTF");
  GSLAM_EXPECT_ERROR(app::read_gltf_splats(dir / "garbage.glb"), "garbage.glb");
  gslam::test::write_text(dir / "nosplat.gltf", R"({"asset": {"version": "2.0"}, "scenes": [{"nodes": []}]})");
  GSLAM_EXPECT_ERROR(app::read_gltf_splats(dir / "nosplat.gltf"), "no KHR_gaussian_splatting primitive");
  gslam::test::write_text(dir / "noscale.gltf", R"({"asset": {"version": "2.0"},
    "extensionsUsed": ["KHR_gaussian_splatting"], "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "name": "n"}],
    "meshes": [{"primitives": [{"mode": 0, "attributes": {"POSITION": 0, "KHR_gaussian_splatting:ROTATION": 0},
      "extensions": {"KHR_gaussian_splatting": {"kernel": "ellipse"}}}]}],
    "buffers": [{"byteLength": 12, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAA"}],
    "bufferViews": [{"buffer": 0, "byteLength": 12}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 1, "type": "VEC3"}]})");
  GSLAM_EXPECT_ERROR(app::read_gltf_splats(dir / "noscale.gltf"), "noscale.gltf", "ROTATION", "components");
}

// A one-splat .gltf whose JSON is `json` with its buffer in `bin` beside it: crafted files.
// `data`: POSITION vec3, ROTATION vec4, SCALE vec3, OPACITY, COLOR_0 vec3 (15 floats).
std::filesystem::path write_crafted(const TempDir& dir, const std::string& name, const std::string& json,
                                    std::vector<float> data = {0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0}) {
  std::ofstream(dir / "crafted.bin", std::ios::binary).write(reinterpret_cast<const char*>(data.data()), 60);
  std::ofstream(dir / name) << json;
  return dir / name;
}

// The accessors of one splat primitive; `override` replaces a piece of the JSON.
std::string crafted_json(const std::string& accessors, const std::string& buffer_uri = "crafted.bin",
                         const std::string& nodes = R"([{"mesh": 0}])") {
  return R"({"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_gaussian_splatting"],
    "buffers": [{"uri": ")" + buffer_uri + R"(", "byteLength": 60}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 60}],
    "accessors": )" + accessors + R"(,
    "meshes": [{"primitives": [{"mode": 0, "attributes": {"POSITION": 0, "KHR_gaussian_splatting:ROTATION": 1,
      "KHR_gaussian_splatting:SCALE": 2, "KHR_gaussian_splatting:OPACITY": 3, "COLOR_0": 4},
      "extensions": {"KHR_gaussian_splatting": {}}}]}],
    "nodes": )" + nodes + R"(, "scenes": [{"nodes": [0]}], "scene": 0})";
}

std::string accessors(const std::string& position_count = "1", const std::string& position_offset = "0",
                      const std::string& color_count = "1") {
  return R"([{"bufferView": 0, "byteOffset": )" + position_offset + R"(, "componentType": 5126, "count": )" + position_count +
         R"(, "type": "VEC3", "min": [0, 0, 0], "max": [0, 0, 0]},
    {"bufferView": 0, "byteOffset": 12, "componentType": 5126, "count": 1, "type": "VEC4"},
    {"bufferView": 0, "byteOffset": 28, "componentType": 5126, "count": 1, "type": "VEC3"},
    {"bufferView": 0, "byteOffset": 40, "componentType": 5126, "count": 1, "type": "SCALAR"},
    {"bufferView": 0, "byteOffset": 44, "componentType": 5126, "count": )" + color_count + R"(, "type": "VEC3"}])";
}

// What gslam writes follows the extension's current text: SCALE linear (never negative) and
// COLOR_0 in linear light, checked on the stored accessors.
TEST(GltfFormat, WritesLinearScalesAndLinearColour) {
  TempDir dir;
  gslam::test::SceneOptions o;
  o.count = 20;
  const splat::Gaussians map = gslam::test::make_random_scene<float>(o).gaussians;
  app::write_gltf(dir / "map.glb", map);
  tinygltf::TinyGLTF loader;
  tinygltf::Model model;
  std::string err, warn;
  ASSERT_TRUE(loader.LoadBinaryFromFile(&model, &err, &warn, (dir / "map.glb").string())) << err;
  const auto& attributes = model.meshes.at(0).primitives.at(0).attributes;
  auto floats = [&](const std::string& name) {
    const tinygltf::Accessor& a = model.accessors.at(static_cast<std::size_t>(attributes.at(name)));
    const tinygltf::BufferView& v = model.bufferViews.at(static_cast<std::size_t>(a.bufferView));
    return reinterpret_cast<const float*>(model.buffers.at(0).data.data() + v.byteOffset + a.byteOffset);
  };
  const float* scale = floats("KHR_gaussian_splatting:SCALE");
  const float* color = floats("COLOR_0");
  const std::size_t k = static_cast<std::size_t>((map.sh_degree + 1) * (map.sh_degree + 1));
  for (std::size_t i = 0; i < map.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(scale[i * 3 + a], 0.f);
      EXPECT_NEAR(scale[i * 3 + a], std::exp(map.log_scales[i * 3 + a]), 1e-6f * scale[i * 3 + a]);
      const float display = std::clamp(map.sh[i * k * 3 + a] * 0.28209479177387814f + 0.5f, 0.f, 1.f);
      EXPECT_NEAR(color[i * 4 + a], app::srgb_to_linear(display), 1e-6f) << "splat " << i;
    }
  }
}

// The rule for files of the older drafts: any negative SCALE means log-scales and display
// COLOR_0 for the whole file; otherwise both are linear.
TEST(GltfFormat, ReadsLinearFilesAndOlderDraftsByTheRule) {
  TempDir dir;
  const float linear_grey = app::srgb_to_linear(0.75f);
  const auto linear = app::read_gltf_splats(write_crafted(dir, "linear.gltf", crafted_json(accessors()),
                                                          {0, 0, 0, 0, 0, 0, 1, 0.5f, 2, 0, 0.5f, linear_grey, linear_grey, linear_grey, 0}));
  EXPECT_FALSE(linear.older_draft);
  const auto& l = linear.primitives.at(0);
  EXPECT_NEAR(l.log_scales[0], std::log(0.5f), 1e-6f);
  EXPECT_NEAR(l.log_scales[1], std::log(2.f), 1e-6f);
  EXPECT_TRUE(std::isfinite(l.log_scales[2])) << "a linear 0 is a finite (tiny) scale";
  EXPECT_NEAR(l.sh[0], (0.75f - 0.5f) / 0.28209479f, 1e-4f);
  const auto older = app::read_gltf_splats(write_crafted(dir, "older.gltf", crafted_json(accessors()),
                                                         {0, 0, 0, 0, 0, 0, 1, -1, 2, 0, 0.5f, 0.75f, 0.75f, 0.75f, 0}));
  EXPECT_TRUE(older.older_draft);
  const auto& o = older.primitives.at(0);
  EXPECT_FLOAT_EQ(o.log_scales[0], -1.f);
  EXPECT_FLOAT_EQ(o.log_scales[1], 2.f);
  EXPECT_NEAR(o.sh[0], (0.75f - 0.5f) / 0.28209479f, 1e-4f);
  bool noticed = false;
  for (const std::string& n : older.notices) noticed = noticed || n.find("log-scales") != std::string::npos;
  EXPECT_TRUE(noticed);
}

TEST(GltfFormat, CraftedFileIsReadWhenWellFormed) {
  TempDir dir;
  const app::GltfSplatScene scene = app::read_gltf_splats(write_crafted(dir, "ok.gltf", crafted_json(accessors())));
  ASSERT_EQ(scene.primitives.size(), 1u);
  EXPECT_EQ(scene.primitives[0].opacities.size(), 1u);
}

// Each reproducer of the hardening issue: a one-line error naming the file and the element.
TEST(GltfFormat, HostileFilesGiveOneLineErrors) {
  TempDir dir;
  // An accessor count whose byte size overflows 64 bits (once a heap overflow).
  GSLAM_EXPECT_ERROR(app::read_gltf_splats(write_crafted(dir, "count.gltf", crafted_json(accessors("4611686018427387904")))),
                     "count.gltf", "POSITION");
  // A byte offset near 2^64 (once wrapped the bounds check and read before the buffer).
  GSLAM_EXPECT_ERROR(
      app::read_gltf_splats(write_crafted(dir, "offset.gltf", crafted_json(accessors("1", "18446744073709551600")))),
      "offset.gltf", "POSITION");
  // COLOR_0 shorter than POSITION (once read past its end).
  GSLAM_EXPECT_ERROR(app::read_gltf_splats(write_crafted(dir, "color.gltf", crafted_json(accessors("1", "0", "0")))),
                     "color.gltf", "COLOR_0", "0 elements, expected 1");
  // A buffer outside the glTF's folder (once read /etc/passwd).
  GSLAM_EXPECT_ERROR(
      app::read_gltf_splats(write_crafted(dir, "escape.gltf", crafted_json(accessors(), "../../../../../../etc/passwd"))),
      "escape.gltf", "outside the glTF's folder");
  // tinygltf joins an absolute URI to the folder too, so it names a file that does not exist.
  GSLAM_EXPECT_ERROR(app::read_gltf_splats(write_crafted(dir, "absolute.gltf", crafted_json(accessors(), "/etc/passwd"))),
                     "absolute.gltf", "/etc/passwd");
  std::filesystem::create_symlink("/etc/passwd", dir / "link.bin");
  GSLAM_EXPECT_ERROR(app::read_gltf_splats(write_crafted(dir, "symlink.gltf", crafted_json(accessors(), "link.bin"))),
                     "symlink.gltf", "outside the glTF's folder");
  // A node graph that shares children: node i has children [i+1, i+1], 2^40 walks once.
  std::string nodes = "[";
  for (int i = 0; i < 40; ++i) nodes += R"({"mesh": 0, "children": [)" + std::to_string(i + 1) + ", " + std::to_string(i + 1) + "]},";
  nodes += R"({"mesh": 0}])";
  GSLAM_EXPECT_ERROR(app::read_gltf_splats(write_crafted(dir, "dag.gltf", crafted_json(accessors(), "crafted.bin", nodes))),
                     "dag.gltf", "is reached twice; glTF nodes must form trees");
  // An index out of range: a message, not vector::_M_range_check.
  std::string bad_view = accessors();
  bad_view.replace(bad_view.find(R"("bufferView": 0)"), 15, R"("bufferView": 9)");
  GSLAM_EXPECT_ERROR(app::read_gltf_splats(write_crafted(dir, "view.gltf", crafted_json(bad_view))), "view.gltf",
                     "buffer view 9 does not exist");
}

}  // namespace
