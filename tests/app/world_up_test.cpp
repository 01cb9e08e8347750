// Which way is up: estimate_world_up on hand-built maps, summary.json's world_up on a generated
// sequence with known truth, and map.glb standing upright in glTF's axes (+Y up) while gslam
// reads it back in the run's world frame.
#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <Eigen/Geometry>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <vector>

#include "app/run_gslam.h"
#include "datasets/synthetic_sequence.h"
#include "io/gltf_io.h"
#include "io/ply_io.h"
#include "io/trajectory.h"
#include "splat/error.h"
#include "support/json_file.h"
#include "support/random_scene.h"
#include "support/temp_dir.h"
#include "viewer/views.h"

namespace {

using gslam::test::TempDir;

double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / M_PI;
}

// A deterministic value in [-1, 1] (the tests need no RNG, only spread).
double wobble(std::size_t i, double frequency) { return std::sin(static_cast<double>(i) * frequency); }

// A room-like map about a true up `up`: cameras' centres at height 0, the floor (4 x 4 m, 1 cm
// noise) at -1.5, a 4 x 3 m wall beside it, and stray points; plus optional extra points.
struct Room {
  Eigen::Vector3d up;
  Eigen::Vector3d a, b;  // horizontal axes
  std::vector<Eigen::Vector3d> points;
  bool floor = true;

  explicit Room(const Eigen::Vector3d& up_in, bool with_floor = true) : up(up_in.normalized()), floor(with_floor) {
    a = up.unitOrthogonal();
    b = up.cross(a);
    std::size_t i = 0;
    for (double s = -2; s <= 2; s += 0.05) {
      for (double t = -2; t <= 2; t += 0.05, ++i) {
        if (floor) points.push_back(s * a + t * b + (-1.5 + 0.01 * wobble(i, 1.7)) * up);
        // The wall: 4 m along a, 3 m high, 2 m away along b.
        if (t <= 1) points.push_back(s * a + 2.0 * b + (t + 0.5) * up + 0.01 * wobble(i, 2.3) * b);
      }
    }
    for (std::size_t k = 0; k < 500; ++k) {  // strays through the room
      points.push_back(1.8 * wobble(k, 0.71) * a + 1.8 * wobble(k, 1.13) * b + 1.4 * wobble(k, 0.37) * up);
    }
  }

  // A horizontal (or `tilt_deg` tilted) square of `side` metres at `height`, 2 cm spacing.
  void add_slab(double height, double side, double tilt_deg) {
    const Eigen::Vector3d normal = Eigen::AngleAxisd(tilt_deg * M_PI / 180.0, a) * up;
    const Eigen::Vector3d u = normal.unitOrthogonal(), v = normal.cross(u);
    for (double s = -side / 2; s <= side / 2; s += 0.02)
      for (double t = -side / 2; t <= side / 2; t += 0.02) points.push_back(s * u + t * v + height * up + 0.3 * a);
  }

  splat::Gaussians map() const {
    splat::Gaussians g;
    g.resize(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
      for (int c = 0; c < 3; ++c) g.means[i * 3 + static_cast<std::size_t>(c)] = static_cast<float>(points[i][c]);
    return g;
  }

  // Ten cameras along a line at height 0, all facing along `a` and rolled 20 degrees: their
  // image-up axes are 20 degrees off the true up, and, sharing one heading, they cannot say
  // better from their right axes either.
  std::vector<Eigen::Isometry3d> tilted_cameras() const {
    std::vector<Eigen::Isometry3d> poses;
    for (int k = 0; k < 10; ++k) {
      Eigen::Matrix3d level;
      level.col(2) = a;                                 // forward
      level.col(1) = -up;                               // image down
      level.col(0) = level.col(1).cross(level.col(2));  // right
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      T.linear() = level * Eigen::AngleAxisd(20.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      T.translation() = (0.2 * k - 1.0) * b - 0.5 * a;
      poses.push_back(T);
    }
    return poses;
  }
};

TEST(WorldUp, FloorPlaneCorrectsTiltedCameras) {
  const Room room(Eigen::Vector3d(0.1, -1.0, 0.2));
  const auto poses = room.tilted_cameras();
  const double camera_error = angle_deg(app::camera_up(poses), room.up);
  EXPECT_GT(camera_error, 15.0) << "the cameras alone should be off (rolled 20 degrees)";
  const app::WorldUp up = app::estimate_world_up(poses, room.map());
  EXPECT_EQ(up.source, app::WorldUp::Source::kFloorPlane);
  EXPECT_STREQ(up.source_name(), "floor plane");
  EXPECT_LT(angle_deg(up.up, room.up), 2.0) << "camera up was off by " << camera_error << " deg";
  EXPECT_NEAR(up.up.norm(), 1.0, 1e-9);
  // Deterministic: the same answer twice.
  const app::WorldUp again = app::estimate_world_up(poses, room.map());
  EXPECT_EQ(again.up, up.up);
}

TEST(WorldUp, PrefersTheLowerPlaneToALargerTableTop) {
  // A table top holding more means than the floor, tilted 8 degrees so that taking it would show.
  Room room(Eigen::Vector3d(0, -1, 0));
  room.add_slab(-0.8, 2.2, 8.0);
  const app::WorldUp up = app::estimate_world_up(room.tilted_cameras(), room.map());
  EXPECT_EQ(up.source, app::WorldUp::Source::kFloorPlane);
  EXPECT_LT(angle_deg(up.up, room.up), 2.0) << "up " << up.up.transpose();
}

TEST(WorldUp, WithoutAFloorKeepsTheCamerasUp) {
  const Room room(Eigen::Vector3d(0.1, -1.0, 0.2), /*with_floor=*/false);
  const auto poses = room.tilted_cameras();
  const app::WorldUp up = app::estimate_world_up(poses, room.map());
  EXPECT_EQ(up.source, app::WorldUp::Source::kCameras);
  EXPECT_STREQ(up.source_name(), "cameras");
  EXPECT_LT(angle_deg(up.up, app::camera_up(poses)), 1e-9);
  // An empty map has no floor either.
  EXPECT_EQ(app::estimate_world_up(poses, splat::Gaussians{}).source, app::WorldUp::Source::kCameras);
}

TEST(WorldUp, PlaneAboveTheCamerasIsNoFloor) {
  // Only a ceiling 1.5 m above the cameras (and the wall): not a floor, whatever its size.
  Room room(Eigen::Vector3d(0, -1, 0), /*with_floor=*/false);
  room.add_slab(1.5, 4.0, 0.0);
  const app::WorldUp up = app::estimate_world_up(room.tilted_cameras(), room.map());
  EXPECT_EQ(up.source, app::WorldUp::Source::kCameras);
}

TEST(GltfWorldUp, RotationTakesUpToPlusYAndTheViewToMinusZ) {
  // A level OpenCV camera (up = -y): the usual 180 degree turn about x.
  const Eigen::Quaterniond level = app::gltf_rotation_for_up(Eigen::Vector3d(0, -2, 0));
  EXPECT_LT((level * Eigen::Vector3d(0, -1, 0) - Eigen::Vector3d::UnitY()).norm(), 1e-12);
  EXPECT_LT((level * Eigen::Vector3d(0, 0, 1) - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
  EXPECT_LT((level * Eigen::Vector3d(1, 0, 0) - Eigen::Vector3d(1, 0, 0)).norm(), 1e-12);
  // A tilted up, and one along the view direction (a camera looking straight down).
  for (const Eigen::Vector3d& up : {Eigen::Vector3d(0.2, -1, 0.4), Eigen::Vector3d(0, 0, -1)}) {
    const Eigen::Quaterniond q = app::gltf_rotation_for_up(up);
    EXPECT_LT((q * up.normalized() - Eigen::Vector3d::UnitY()).norm(), 1e-12) << up.transpose();
    EXPECT_NEAR(q.norm(), 1.0, 1e-12);
  }
  EXPECT_THROW(app::gltf_rotation_for_up(Eigen::Vector3d::Zero()), splat::Error);
}

// The node of a written .glb file, read raw.
tinygltf::Model load_raw(const std::filesystem::path& path) {
  tinygltf::TinyGLTF loader;
  tinygltf::Model model;
  std::string err, warn;
  EXPECT_TRUE(loader.LoadBinaryFromFile(&model, &err, &warn, path.string())) << err;
  return model;
}

TEST(GltfWorldUp, WrittenUprightAndReadBackInTheWorldFrame) {
  TempDir dir;
  gslam::test::SceneOptions o;
  o.count = 40;
  o.sh_degree = 1;
  const splat::Gaussians map = gslam::test::make_random_scene<float>(o).gaussians;
  const Eigen::Vector3d up(0.2, -1.0, 0.3);
  const Eigen::Quaterniond q = app::gltf_rotation_for_up(up);
  app::write_gltf(dir / "map.glb", map, q);

  // The node rotation stands the map upright in glTF's axes: the up lands on +Y.
  const tinygltf::Model model = load_raw(dir / "map.glb");
  ASSERT_EQ(model.nodes.size(), 1u);
  const tinygltf::Node& node = model.nodes[0];
  ASSERT_EQ(node.rotation.size(), 4u);
  const Eigen::Quaterniond stored(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
  EXPECT_LT((stored * up.normalized() - Eigen::Vector3d::UnitY()).norm(), 1e-9)
      << "stored up " << (stored * up).transpose();
  EXPECT_TRUE(node.matrix.empty() && node.translation.empty() && node.scale.empty());

  // gslam reads it back in the world frame it was written from, bit for bit.
  const splat::Gaussians back = app::to_gaussians(app::read_gltf_splats(dir / "map.glb"));
  ASSERT_EQ(back.size(), map.size());
  EXPECT_EQ(back.means, map.means);
  EXPECT_EQ(back.sh, map.sh);
  for (std::size_t i = 0; i < map.rotations.size(); ++i) {
    const float* r = &map.rotations[i / 4 * 4];
    const double norm = std::sqrt(double(r[0]) * r[0] + double(r[1]) * r[1] + double(r[2]) * r[2] + double(r[3]) * r[3]);
    EXPECT_NEAR(back.rotations[i], map.rotations[i] / norm, 1e-6) << "value " << i;
  }

  // Without gslam's mark the same node is a third party's transform, applied as before: the
  // means come out in glTF's axes.
  tinygltf::Model unmarked = model;
  unmarked.nodes[0].extras = tinygltf::Value();
  tinygltf::TinyGLTF writer;
  ASSERT_TRUE(writer.WriteGltfSceneToFile(&unmarked, (dir / "unmarked.glb").string(), true, true, false, true));
  const splat::Gaussians turned = app::to_gaussians(app::read_gltf_splats(dir / "unmarked.glb"));
  ASSERT_EQ(turned.size(), map.size());
  for (std::size_t i = 0; i < map.size(); ++i) {
    const Eigen::Vector3d p(map.means[i * 3], map.means[i * 3 + 1], map.means[i * 3 + 2]);
    const Eigen::Vector3d expected = q * p;
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(turned.means[i * 3 + static_cast<std::size_t>(c)], expected[c], 1e-5) << "splat " << i;
    }
  }
}

TEST(GltfWorldUp, IdentityWritesNoNodeTransform) {
  TempDir dir;
  gslam::test::SceneOptions o;
  o.count = 10;
  app::write_gltf(dir / "map.glb", gslam::test::make_random_scene<float>(o).gaussians);
  const tinygltf::Model model = load_raw(dir / "map.glb");
  ASSERT_EQ(model.nodes.size(), 1u);
  EXPECT_TRUE(model.nodes[0].rotation.empty());
  EXPECT_FALSE(model.nodes[0].extras.IsObject());
}

using gslam::test::read_json;

// Through the CLI: the generated room's up (world -y, the generator's y points down) seen from
// the first camera, against what reconstruct records; map.glb upright; render's orbit using it.
TEST(WorldUpCli, ReconstructRecordsTheGeneratedRoomsUp) {
  TempDir dir;
  app::SyntheticOptions o;
  o.frames = 10;
  app::write_synthetic_sequence(dir / "seq", o);
  gslam::test::write_text(dir / "quick.json", R"({"refine_passes": 0})");
  const auto r = run_gslam("reconstruct " + (dir / "seq").string() + " --out " + (dir / "run").string() +
                           " --config " + (dir / "quick.json").string() + " --backend cpu");
  ASSERT_EQ(r.exit_code, 0) << r.output;

  const nlohmann::json summary = read_json(dir / "run" / "summary.json");
  ASSERT_TRUE(summary.contains("world_up")) << summary.dump();
  const nlohmann::json& w = summary.at("world_up");
  const Eigen::Vector3d recorded(w.at("x").get<double>(), w.at("y").get<double>(), w.at("z").get<double>());
  // gslam's world is the first camera's frame: the truth's up there is R_first^T * (0, -1, 0).
  const auto truth = app::read_tum_trajectory(dir / "seq" / "groundtruth.txt");
  ASSERT_FALSE(truth.empty());
  const Eigen::Vector3d true_up = truth.front().T_world_cam.linear().transpose() * Eigen::Vector3d(0, -1, 0);
  const double error = angle_deg(recorded, true_up);
  EXPECT_LT(error, 3.0) << "recorded " << recorded.transpose() << " (" << w.at("source") << "), truth "
                        << true_up.transpose();
  EXPECT_EQ(w.at("source").get<std::string>(), "floor plane") << "the room's floor is in view";
  RecordProperty("world_up_error_deg", std::to_string(error));

  // map.glb: upright in glTF's axes, and read back as map.ply holds the map.
  const tinygltf::Model model = load_raw(dir / "run" / "map.glb");
  ASSERT_EQ(model.nodes.at(0).rotation.size(), 4u);
  const auto& n = model.nodes[0].rotation;
  const Eigen::Quaterniond q(n[3], n[0], n[1], n[2]);
  EXPECT_LT(angle_deg(q * true_up, Eigen::Vector3d::UnitY()), 3.0);
  const splat::Gaussians glb = app::to_gaussians(app::read_gltf_splats(dir / "run" / "map.glb"));
  EXPECT_EQ(glb.means, app::read_ply(dir / "run" / "map.ply").gaussians.means);

  // render of the bare map.ply orbits about the recorded up.
  const auto render = run_gslam("render " + (dir / "run" / "map.ply").string() + " --out " + (dir / "views").string() +
                                " --orbit 2 --size 40x30 --backend cpu");
  ASSERT_EQ(render.exit_code, 0) << render.output;
  EXPECT_NE(render.output.find("(from summary.json world_up)"), std::string::npos) << render.output;
}

}  // namespace
