// Place recognition: ORB features with depth, matched and verified by RANSAC, give the relative
// pose of two views of the same place, and nothing for views that share no place.
#include "tracking/place_recognition.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <random>

#include "datasets/dataset.h"
#include "datasets/synthetic_sequence.h"
#include "support/synthetic_dataset.h"
#include "support/temp_dir.h"

namespace {

TEST(PlaceRecognition, VerifiedMatchGivesTheRelativePoseOfTwoViews) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o;
  o.frames = 11;  // the frames used, of a 30-frame path
  o.path_frames = 30;
  const app::Dataset d = gslam::test::synthetic_dataset(dir / "seq", o);
  tracking::PlaceDatabase db;
  for (std::size_t k : {0u, 10u}) db.add(k, tracking::extract_place_features(d.load(k)));
  ASSERT_EQ(db.size(), 2u);
  const tracking::PlaceFeatures query = tracking::extract_place_features(d.load(6));
  EXPECT_GT(query.points.size(), 100u);
  const auto matches = db.query(query, [](std::size_t k) { return k == 0; });
  ASSERT_FALSE(matches.empty());
  const tracking::PlaceMatch& m = matches.front();
  EXPECT_EQ(m.keyframe, 0u);
  const Eigen::Isometry3d truth = d.entries[0].T_world_cam_truth->inverse() * *d.entries[6].T_world_cam_truth;
  EXPECT_LT((m.T_keyframe_query.translation() - truth.translation()).norm(), 0.02) << m.inliers << " inliers";
  EXPECT_LT(Eigen::AngleAxisd(m.T_keyframe_query.linear().transpose() * truth.linear()).angle(), 0.01);
  EXPECT_GE(m.inliers, 25);
  EXPECT_LT(m.rms_m, 0.02);
  // Its information is positive definite (it has a Cholesky factor): every direction of the pose
  // is observed. (Not through its eigenvalues: Eigen's 6x6 eigensolver took 30 s to compile.)
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  EXPECT_EQ(Eigen::LLT<Matrix6d>(m.information).info(), Eigen::Success);
  EXPECT_TRUE(db.query(query, [](std::size_t) { return false; }).empty()) << "nothing eligible, nothing matched";
}

TEST(PlaceRecognition, RansacFindsTheRigidMotionAmongOutliers) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1, 1);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.3, -0.2, 0.5);
  std::vector<Eigen::Vector3f> from, to;
  for (int i = 0; i < 100; ++i) {
    const Eigen::Vector3f p(u(rng), u(rng), 2 + u(rng));
    from.push_back(p);
    // 40% of the matches are wrong.
    to.push_back(i % 5 < 2 ? Eigen::Vector3f(u(rng), u(rng), 2 + u(rng)) : (T * p.cast<double>()).cast<float>());
  }
  const auto m = tracking::fit_rigid_ransac(from, to, {});
  ASSERT_TRUE(m.has_value());
  EXPECT_EQ(m->inliers, 60);
  EXPECT_LT((m->T_keyframe_query.matrix() - T.matrix()).cwiseAbs().maxCoeff(), 1e-5);
  // Pure outliers: no fit.
  std::vector<Eigen::Vector3f> noise;
  for (int i = 0; i < 100; ++i) noise.emplace_back(u(rng), u(rng), 2 + u(rng));
  EXPECT_FALSE(tracking::fit_rigid_ransac(from, noise, {}).has_value());
}

}  // namespace
