#include <gtest/gtest.h>

#include "io/trajectory.h"
#include "viewer/views.h"
#include "support/expect_error.h"
#include "support/temp_dir.h"

namespace {

using gslam::test::TempDir;

TEST(TumTrajectory, RoundTripKeepsPosesAndTimestamps) {
  TempDir dir;
  std::vector<app::StampedPose> poses(3);
  for (int i = 0; i < 3; ++i) {
    poses[i].timestamp = 1341841873.273798 + 0.033 * i;
    poses[i].T_world_cam = Eigen::Translation3d(0.1 * i, -0.2, 1.5) *
                           Eigen::AngleAxisd(0.3 * i, Eigen::Vector3d(0.2, 1, 0.1).normalized());
  }
  app::write_tum_trajectory(dir / "t.txt", poses);
  const auto back = app::read_tum_trajectory(dir / "t.txt");
  ASSERT_EQ(back.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(back[i].timestamp, poses[i].timestamp, 1e-6);
    EXPECT_TRUE(back[i].T_world_cam.isApprox(poses[i].T_world_cam, 1e-8)) << "pose " << i;
  }
}

TEST(TumTrajectory, MalformedLinesAreErrorsNamingTheLine) {
  TempDir dir;
  gslam::test::write_text(dir / "short.txt", "# comment\n1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 1\n");
  GSLAM_EXPECT_ERROR(app::read_tum_trajectory(dir / "short.txt"), "short.txt", "line 3 has 7 values");
  gslam::test::write_text(dir / "word.txt", "1.0 0 0 zero 0 0 0 1\n");
  GSLAM_EXPECT_ERROR(app::read_tum_trajectory(dir / "word.txt"), "line 1", "'zero' is not a finite number");
  gslam::test::write_text(dir / "nan.txt", "1.0 0 0 nan 0 0 0 1\n");
  GSLAM_EXPECT_ERROR(app::read_tum_trajectory(dir / "nan.txt"), "line 1", "not a finite number");
  gslam::test::write_text(dir / "quat.txt", "1.0 0 0 0 0 0 0 0\n");
  GSLAM_EXPECT_ERROR(app::read_tum_trajectory(dir / "quat.txt"), "line 1", "quaternion norm is 0");
  GSLAM_EXPECT_ERROR(app::read_tum_trajectory(dir / "none.txt"), "none.txt", "cannot open");
}

TEST(CameraOptions, ParsesIntrinsicsAndSizesAndRejectsNonsense) {
  const app::Intrinsics k = app::parse_intrinsics("535.4,539.2,320.1,247.6,640,480");
  EXPECT_DOUBLE_EQ(k.fx, 535.4);
  EXPECT_EQ(k.height, 480);
  GSLAM_EXPECT_ERROR(app::parse_intrinsics("1,2,3"), "intrinsics '1,2,3'");
  GSLAM_EXPECT_ERROR(app::parse_intrinsics("500,500,320,240,0,480"), "intrinsics");
  EXPECT_EQ(app::parse_size("640x480"), std::make_pair(640, 480));
  GSLAM_EXPECT_ERROR(app::parse_size("0x480"), "size '0x480'");
  GSLAM_EXPECT_ERROR(app::parse_size("99999x10"), "size '99999x10'");
}

TEST(CameraOptions, OrbitCamerasLookAtTheCentre) {
  app::MapExtent extent;
  extent.center = Eigen::Vector3d(1, 2, 3);
  extent.radius = 0.5;
  const auto cams = app::orbit_cameras(extent, 8, 64, 48, Eigen::Vector3d::UnitZ());
  ASSERT_EQ(cams.size(), 8u);
  for (const auto& cam : cams) {
    const Eigen::Vector3d c = cam.T_cam_world * extent.center;
    EXPECT_NEAR(c.x(), 0, 1e-9);
    EXPECT_NEAR(c.y(), 0, 1e-9);
    EXPECT_NEAR(c.z(), 1.25, 1e-9);
    // World up appears upward in the image (negative camera y).
    EXPECT_LT((cam.T_cam_world.linear() * Eigen::Vector3d::UnitZ()).y(), 0);
    EXPECT_NO_THROW(cam.validate("orbit"));
  }
}

// A run's cameras: an arc about an object at (0, 0, 2) in a world whose up is (0.3, -1, 0.2)
// (not an axis), each pitched 25 degrees down at it and never rolled.
std::vector<Eigen::Isometry3d> arc_of_cameras(const Eigen::Vector3d& up, const Eigen::Vector3d& object) {
  std::vector<Eigen::Isometry3d> poses;
  const Eigen::Vector3d a = up.unitOrthogonal(), b = up.cross(a);
  for (int i = 0; i < 30; ++i) {
    const double angle = 0.04 * i;  // a 70 degree arc, as a hand-held sweep gives
    const Eigen::Vector3d eye = object + 1.5 * (std::cos(angle) * a + std::sin(angle) * b) + 0.7 * up;
    poses.push_back(app::look_at(eye, object, up));
  }
  return poses;
}

TEST(CameraOptions, OrbitOfARunFindsItsUpAndWhatTheCamerasLookedAt) {
  const Eigen::Vector3d up = Eigen::Vector3d(0.3, -1, 0.2).normalized(), object(0, 0, 2);
  const std::vector<Eigen::Isometry3d> poses = arc_of_cameras(up, object);
  EXPECT_GT(app::camera_up(poses).dot(up), 1 - 1e-9) << "the cameras' own image-up is tilted 25 degrees from it";
  app::MapExtent extent;
  extent.center = object + Eigen::Vector3d(0.4, 0, 0.3);  // the map's bulk is off the object
  extent.radius = 1;
  const app::Intrinsics k{50, 50, 32, 24, 64, 48};
  const auto orbit = app::orbit_at_camera_height(extent, poses, 12, k);
  ASSERT_EQ(orbit.size(), 12u);
  for (const auto& cam : orbit) {
    const Eigen::Vector3d c = cam.T_cam_world * object;
    EXPECT_NEAR(c.x(), 0, 1e-6) << "looks at what the cameras looked at";
    EXPECT_NEAR(c.y(), 0, 1e-6);
    const Eigen::Vector3d eye = cam.T_cam_world.inverse().translation();
    EXPECT_NEAR((eye - object).dot(up), 0.7, 1e-6) << "at the cameras' height";
    EXPECT_NEAR(((eye - object) - (eye - object).dot(up) * up).norm(), 1.5, 1e-6) << "at their distance";
    EXPECT_EQ(cam.width, 64);
  }
}

TEST(CameraOptions, NovelPathRunsNearTheRecordedOneButNeverAtIt) {
  const std::vector<Eigen::Isometry3d> poses = arc_of_cameras(Eigen::Vector3d::UnitZ(), Eigen::Vector3d::Zero());
  const Eigen::Vector3d offset(0.1, -0.05, 0);
  const auto path = app::novel_path(poses, 45, offset);
  ASSERT_EQ(path.size(), 45u);
  for (const auto& T : path) {
    double nearest = 1e9;
    for (const auto& P : poses) nearest = std::min(nearest, (T.translation() - P.translation()).norm());
    EXPECT_GT(nearest, 0.05) << "offset from every recorded camera";
    EXPECT_LT(nearest, 0.2) << "yet near the recorded path";
    EXPECT_NEAR(T.linear().determinant(), 1, 1e-9);
  }
  // Without an offset the path passes between the recorded poses, in order.
  const auto plain = app::novel_path(poses, 29, Eigen::Vector3d::Zero(), 0);
  for (std::size_t i = 0; i < plain.size(); ++i) {
    const Eigen::Vector3d mid = 0.5 * (poses[i].translation() + poses[i + 1].translation());
    EXPECT_LT((plain[i].translation() - mid).norm(), 0.02) << i;
  }
  EXPECT_THROW(app::novel_path({}, 3, offset), splat::Error);
}

}  // namespace
