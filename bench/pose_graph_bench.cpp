// Pose-graph optimization time: N keyframes on a walk that laps a room, odometry edges to the
// previous two keyframes (drifting measurements), and a loop edge every 50 keyframes.
#include <random>

#include <benchmark/benchmark.h>

#include "splat/se3.h"
#include "tracking/pose_graph.h"

namespace {

struct Graph {
  std::vector<Eigen::Isometry3d> poses;  // the drifting odometry chain: where solving starts
  std::vector<tracking::PoseGraphEdge> edges;
};

Graph make_graph(int n) {
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0, 2e-3);
  std::vector<Eigen::Isometry3d> truth;
  for (int k = 0; k < n; ++k) {
    const double a = 2 * M_PI * k / 100.0;  // a lap every 100 keyframes
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(-a, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(2 * std::sin(a), 0.1 * std::sin(7 * a), 2 - 2 * std::cos(a));
    truth.push_back(T);
  }
  auto measured = [&](int i, int j) {
    splat::Vector6d e;
    for (int c = 0; c < 6; ++c) e[c] = noise(rng);
    e[4] += 2e-3;
    tracking::PoseGraphEdge edge;
    edge.i = static_cast<std::size_t>(i), edge.j = static_cast<std::size_t>(j);
    edge.T_i_j = truth[edge.i].inverse() * truth[edge.j] * splat::se3_exp(e);
    edge.information = Eigen::Matrix<double, 6, 6>::Identity() * 2.5e5;
    return edge;
  };
  Graph g;
  g.poses = {truth[0]};
  for (int k = 1; k < n; ++k) {
    g.edges.push_back(measured(k - 1, k));
    g.poses.push_back(g.poses.back() * g.edges.back().T_i_j);
    if (k >= 2) g.edges.push_back(measured(k - 2, k));
    if (k >= 100 && k % 50 == 0) {
      g.edges.push_back(measured(k - 100, k));
      g.edges.back().loop = true;
    }
  }
  return g;
}

void BM_PoseGraph(benchmark::State& state) {
  const Graph g = make_graph(static_cast<int>(state.range(0)));
  std::size_t accepted = 0;
  for (auto _ : state) {
    const tracking::PoseGraphResult r = tracking::optimize_pose_graph(g.poses, g.edges, {0});
    accepted = 0;
    for (std::size_t e = 0; e < g.edges.size(); ++e) accepted += g.edges[e].loop && r.accepted[e];
    benchmark::DoNotOptimize(r.poses.data());
  }
  state.counters["edges"] = static_cast<double>(g.edges.size());
  state.counters["loops_accepted"] = static_cast<double>(accepted);
}
BENCHMARK(BM_PoseGraph)->Arg(100)->Arg(500)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
