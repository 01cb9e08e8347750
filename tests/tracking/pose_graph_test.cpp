// The keyframe pose graph: drift removed by a loop, a wrong loop rejected, the residual the
// se(3) log of the edge error.
#include <random>

#include <gtest/gtest.h>

#include "splat/error.h"
#include "splat/se3.h"
#include "tracking/pose_graph.h"

namespace {

using Isometry = Eigen::Isometry3d;
using Info = Eigen::Matrix<double, 6, 6>;

// A camera walking a 4 m circle in 60 steps (camera-to-world), looking along it.
std::vector<Isometry> circle(int n) {
  std::vector<Isometry> poses;
  for (int k = 0; k < n; ++k) {
    const double a = 2 * M_PI * k / n;
    Isometry T = Isometry::Identity();
    T.linear() = Eigen::AngleAxisd(-a, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(2 * std::sin(a), 0, 2 - 2 * std::cos(a));
    poses.push_back(T);
  }
  return poses;
}

// Odometry edges between consecutive poses, each measurement off by a small yaw bias and noise
// (how visual odometry drifts), and the poses chained from them.
struct Odometry {
  std::vector<tracking::PoseGraphEdge> edges;
  std::vector<Isometry> chained;
};
Odometry drifting_odometry(const std::vector<Isometry>& truth) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0, 1e-3);
  Odometry o;
  o.chained = {truth[0]};
  for (std::size_t k = 1; k < truth.size(); ++k) {
    splat::Vector6d error;
    for (int c = 0; c < 6; ++c) error[c] = noise(rng);
    error[4] += 0.004;  // 0.23 degrees of yaw a step
    tracking::PoseGraphEdge e;
    e.i = k - 1, e.j = k;
    e.T_i_j = truth[k - 1].inverse() * truth[k] * splat::se3_exp(error);
    e.information = Info::Identity() * 1e4;
    o.edges.push_back(e);
    o.chained.push_back(o.chained.back() * e.T_i_j);
  }
  return o;
}

double rmse(const std::vector<Isometry>& a, const std::vector<Isometry>& b) {
  double sum = 0;
  for (std::size_t k = 0; k < a.size(); ++k) sum += (a[k].translation() - b[k].translation()).squaredNorm();
  return std::sqrt(sum / static_cast<double>(a.size()));
}

tracking::PoseGraphEdge loop_edge(std::size_t i, std::size_t j, const Isometry& T_i_j) {
  tracking::PoseGraphEdge e;
  e.i = i, e.j = j, e.T_i_j = T_i_j, e.loop = true;
  e.information = Info::Identity() * 1e4;
  return e;
}

TEST(PoseGraph, LoopRemovesOdometryDrift) {
  const std::vector<Isometry> truth = circle(60);
  Odometry odometry = drifting_odometry(truth);
  const double drift = rmse(odometry.chained, truth);
  ASSERT_GT(drift, 0.05) << "the test needs drift to remove";
  std::vector<tracking::PoseGraphEdge> edges = odometry.edges;
  edges.push_back(loop_edge(59, 0, truth[59].inverse() * truth[0]));
  const tracking::PoseGraphResult r = tracking::optimize_pose_graph(odometry.chained, edges, {0});
  EXPECT_TRUE(r.accepted.back());
  EXPECT_LT(rmse(r.poses, truth), drift / 5) << "drift " << drift;
  EXPECT_LT(r.final_cost, r.initial_cost);
}

TEST(PoseGraph, WrongLoopIsRejectedAndDoesNotBendTheGraph) {
  const std::vector<Isometry> truth = circle(60);
  Odometry odometry = drifting_odometry(truth);
  std::vector<tracking::PoseGraphEdge> edges = odometry.edges;
  edges.push_back(loop_edge(59, 0, truth[59].inverse() * truth[0]));
  // Two places that look alike: frame 30 matched to frame 0 as if it stood there.
  edges.push_back(loop_edge(30, 0, Isometry::Identity()));
  const tracking::PoseGraphResult r = tracking::optimize_pose_graph(odometry.chained, edges, {0});
  EXPECT_TRUE(r.accepted[edges.size() - 2]) << "chi2 " << r.chi2[edges.size() - 2];
  EXPECT_FALSE(r.accepted.back()) << "chi2 " << r.chi2.back();
  EXPECT_LT(rmse(r.poses, truth), rmse(odometry.chained, truth) / 5);
}

// A walk of 40 keyframes along a line, 2 cm apart, its odometry exact to 0.1 mm but for one
// edge, where a frame aligned to someone walking past put a 12 cm jump sideways. Two loops from
// the walk's end to its start, each measured exactly, reveal it.
struct Jump {
  std::vector<Isometry> truth;
  Odometry odometry;
  tracking::PoseGraphEdge first, second;  // loops 38 -> 2 and 39 -> 3
};
Jump odometry_with_a_jump() {
  Jump j;
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0, 1e-4);
  for (int k = 0; k < 40; ++k) j.truth.push_back(Isometry(Eigen::Translation3d(0, 0, 0.02 * k)));
  j.odometry.chained = {j.truth[0]};
  for (std::size_t k = 1; k < j.truth.size(); ++k) {
    splat::Vector6d error;
    for (int c = 0; c < 6; ++c) error[c] = noise(rng);
    if (k == 21) error[0] += 0.12;
    tracking::PoseGraphEdge e;
    e.i = k - 1, e.j = k;
    e.T_i_j = j.truth[k - 1].inverse() * j.truth[k] * splat::se3_exp(error);
    e.information = Info::Identity() * 1e6;  // dense alignment: millimetres
    j.odometry.edges.push_back(e);
    j.odometry.chained.push_back(j.odometry.chained.back() * e.T_i_j);
  }
  j.first = loop_edge(2, 38, j.truth[2].inverse() * j.truth[38]);
  j.second = loop_edge(3, 39, j.truth[3].inverse() * j.truth[39]);
  j.first.information = j.second.information = Info::Identity() * 1e6;  // as sure as the odometry
  return j;
}

TEST(PoseGraph, AJumpIsConfirmedByASecondLoopAndClosed) {
  const Jump j = odometry_with_a_jump();
  std::vector<tracking::PoseGraphEdge> edges = j.odometry.edges;
  edges.push_back(j.first);
  EXPECT_FALSE(tracking::optimize_pose_graph(j.odometry.chained, edges, {0}).accepted.back())
      << "one loop revealing 12 cm over 80 cm of path is outside the drift budget";
  ASSERT_TRUE(tracking::loops_agree(j.odometry.chained, j.second, j.first))
      << "both reveal the same jump";
  edges.back().confirmed = true;
  tracking::PoseGraphEdge second = j.second;
  second.confirmed = true;
  edges.push_back(second);
  const tracking::PoseGraphResult r = tracking::optimize_pose_graph(j.odometry.chained, edges, {0});
  ASSERT_TRUE(r.accepted.back() && r.accepted[edges.size() - 2]);
  // The walk's end is where the loops measured it from its start.
  for (const tracking::PoseGraphEdge* loop : {&j.first, &j.second}) {
    const Isometry error = (r.poses[loop->i].inverse() * r.poses[loop->j]).inverse() * loop->T_i_j;
    EXPECT_LT(error.translation().norm(), 0.005) << "loop " << loop->i << " -> " << loop->j;
  }
}

TEST(PoseGraph, LookAlikePlacesAreNotConfirmedByRepeatingThemselves) {
  const Jump j = odometry_with_a_jump();
  // The walk's end seen as if it stood at the start, turned a quarter (a symmetric pattern),
  // twice, from consecutive keyframes: the two agree with each other, not with the true loop.
  const Isometry turn(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()));
  tracking::PoseGraphEdge a = loop_edge(2, 38, turn), b = loop_edge(3, 39, turn);
  EXPECT_TRUE(tracking::loops_agree(j.odometry.chained, a, b));
  EXPECT_FALSE(tracking::loops_agree(j.odometry.chained, a, j.second));
  a.confirmed = b.confirmed = true;
  std::vector<tracking::PoseGraphEdge> edges = j.odometry.edges;
  edges.push_back(a);
  edges.push_back(b);
  const tracking::PoseGraphResult r = tracking::optimize_pose_graph(j.odometry.chained, edges, {0});
  EXPECT_FALSE(r.accepted.back() || r.accepted[edges.size() - 2])
      << "90 degrees is outside even a confirmed budget";
}

TEST(PoseGraph, ResidualIsTheLogOfTheEdgeError) {
  // Two poses, the second off its measurement by a known twist: with identity information the
  // edge's chi-square before solving is that twist's squared norm.
  splat::Vector6d twist;
  twist << 0.03, -0.02, 0.01, 0.2, -0.1, 0.3;
  const Isometry a = splat::se3_exp((splat::Vector6d() << 1, 2, 3, 0.1, 0.2, 0.3).finished());
  const Isometry z = splat::se3_exp((splat::Vector6d() << 0.5, 0, 0, 0, 0.4, 0).finished());
  tracking::PoseGraphEdge e;
  e.i = 0, e.j = 1, e.T_i_j = z;
  tracking::PoseGraphConfig config;
  config.max_iterations = 0;
  const auto r = tracking::optimize_pose_graph({a, a * z * splat::se3_exp(twist)}, {e}, {0}, config);
  EXPECT_NEAR(r.initial_cost, twist.squaredNorm(), 1e-9);
  // Solved, the free pose moves onto its measurement.
  config.max_iterations = 50;
  const auto solved = tracking::optimize_pose_graph({a, a * z * splat::se3_exp(twist)}, {e}, {0}, config);
  EXPECT_LT((solved.poses[1].matrix() - (a * z).matrix()).cwiseAbs().maxCoeff(), 1e-8);
}

TEST(PoseGraph, RefusesGraphsThatCannotBeSolved) {
  const std::vector<Isometry> two(2, Isometry::Identity());
  tracking::PoseGraphEdge e;
  e.i = 0, e.j = 5;
  EXPECT_THROW(tracking::optimize_pose_graph(two, {e}, {0}), splat::Error);
  e.j = 1;
  EXPECT_THROW(tracking::optimize_pose_graph(two, {e}, {}), splat::Error);
  e.information(2, 2) = -1;
  EXPECT_THROW(tracking::optimize_pose_graph(two, {e}, {0}), splat::Error);
}

}  // namespace
