#include "slam/back_end.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <string>

#include "splat/error.h"

namespace app {
namespace {

// The information of an alignment's edge, made positive definite: a direction the alignment
// could not observe (a flat wall's slide) gets a vanishing weight rather than none.
Eigen::Matrix<double, 6, 6> edge_information(const Eigen::Matrix<double, 6, 6>& information) {
  const double scale = std::max(information.trace() / 6, 1.0);
  return 0.5 * (information + information.transpose()) + 1e-9 * scale * Eigen::Matrix<double, 6, 6>::Identity();
}

// The pose graph solved for the keyframes from `first` on alone, with every keyframe outside
// them that an edge links them to held where it is: the cost stays that of the window however
// long the run (loops solve the whole graph). The poses of all keyframes, the others unmoved.
std::vector<Eigen::Isometry3d> solve_window(const std::vector<Eigen::Isometry3d>& poses,
                                            const std::vector<tracking::PoseGraphEdge>& edges, std::size_t first,
                                            const tracking::PoseGraphConfig& config) {
  std::vector<std::size_t> node(poses.size(), poses.size());  // keyframe -> window node
  std::vector<std::size_t> keyframe;                          // window node -> keyframe
  std::vector<std::size_t> fixed;
  const auto add = [&](std::size_t k, bool hold) {
    if (node[k] != poses.size()) return;
    node[k] = keyframe.size();
    keyframe.push_back(k);
    if (hold) fixed.push_back(node[k]);
  };
  for (std::size_t k = first; k < poses.size(); ++k) add(k, k == 0);
  std::vector<tracking::PoseGraphEdge> window;
  for (const tracking::PoseGraphEdge& e : edges) {
    if (e.i < first && e.j < first) continue;
    add(e.i, true), add(e.j, true);  // a neighbour outside the window: held
    tracking::PoseGraphEdge w = e;
    w.i = node[e.i], w.j = node[e.j];
    window.push_back(w);
  }
  if (fixed.empty()) fixed.push_back(node[first]);  // nothing links the window to the rest: its first holds it
  std::vector<Eigen::Isometry3d> initial;
  for (std::size_t k : keyframe) initial.push_back(poses[k]);
  const tracking::PoseGraphResult solved = tracking::optimize_pose_graph(initial, window, fixed, config);
  std::vector<Eigen::Isometry3d> out = poses;
  for (std::size_t n = 0; n < keyframe.size(); ++n) out[keyframe[n]] = solved.poses[n];
  return out;
}

}  // namespace

std::vector<tracking::PoseGraphEdge> BackEnd::edges_among(std::size_t keyframes) const {
  std::vector<tracking::PoseGraphEdge> edges;
  std::lock_guard lock(graph_mutex_);
  std::copy_if(edges_.begin(), edges_.end(), std::back_inserter(edges),
               [&](const tracking::PoseGraphEdge& e) { return e.i < keyframes && e.j < keyframes; });
  return edges;
}

BackEnd::BackEnd(const SlamConfig& config) : config_(config), places_(config.loop_closure.places) {}

void BackEnd::add_odometry_edge(std::size_t reference, std::size_t keyframe, const Eigen::Isometry3d& T_reference_keyframe,
                                const Eigen::Matrix<double, 6, 6>& information) {
  tracking::PoseGraphEdge edge;
  edge.i = reference, edge.j = keyframe;
  edge.T_i_j = T_reference_keyframe;
  edge.information = edge_information(information);
  std::lock_guard lock(graph_mutex_);
  edges_.push_back(edge);
}

splat::RgbdFrame BackEnd::thumbnail(const splat::RgbdFrame& frame) const {
  const int factor = std::max(1, frame.width() / config_.loop_closure.dense_width);
  return splat::downsample(frame, factor);
}

std::optional<BackEnd::Placement> BackEnd::place(const splat::RgbdFrame& frame,
                                                 const std::function<bool(std::size_t)>& eligible) {
  return place(thumbnail(frame), tracking::extract_place_features(frame, config_.loop_closure.places), eligible);
}

std::optional<BackEnd::Placement> BackEnd::place(const splat::RgbdFrame& thumb, const tracking::PlaceFeatures& features,
                                                 const std::function<bool(std::size_t)>& eligible) {
  std::vector<tracking::PlaceMatch> matches;
  splat::RgbdFrame matched;
  {
    std::lock_guard lock(places_mutex_);
    matches = places_.query(features, eligible);
    if (matches.empty()) return std::nullopt;
    const auto it = std::find_if(thumbnails_.begin(), thumbnails_.end(),
                                 [&](const auto& t) { return t.first == matches.front().keyframe; });
    if (it == thumbnails_.end()) return std::nullopt;
    matched = it->second;
  }
  const tracking::PlaceMatch& m = matches.front();
  // Dense alignment of the two views from the RANSAC estimate.
  tracking::OdometryConfig dense = config_.odometry;
  dense.finest_width = matched.width();
  const tracking::OdometryFrame reference(matched, dense), current(thumb, dense);
  const tracking::OdometryResult aligned = tracking::align_rgbd(reference, current, m.T_keyframe_query.inverse(), dense);
  if (!aligned.converged) return std::nullopt;
  return Placement{m.keyframe, aligned.T_cur_ref.inverse(), edge_information(aligned.information),
                   m.inliers, aligned.depth_spread};
}

std::optional<BackEnd::Loop> BackEnd::close_loop(const splat::RgbdFrame& frame, std::size_t keyframe,
                                                 const std::vector<Eigen::Isometry3d>& poses) {
  const LoopClosureConfig& lc = config_.loop_closure;
  tracking::PlaceFeatures features = tracking::extract_place_features(frame, lc.places);
  const splat::RgbdFrame thumb = thumbnail(frame);
  const std::size_t separation = static_cast<std::size_t>(lc.min_separation);
  const std::optional<Placement> found = place(thumb, features, [&](std::size_t k) { return k + separation <= keyframe; });
  {
    std::lock_guard lock(places_mutex_);
    places_.add(keyframe, std::move(features));
    thumbnails_.emplace_back(keyframe, thumb);
  }
  if (!found) return std::nullopt;
  tracking::PoseGraphEdge loop;
  loop.i = found->keyframe, loop.j = keyframe, loop.loop = true;
  loop.T_i_j = found->T_keyframe_frame;
  loop.information = found->information;
  std::vector<tracking::PoseGraphEdge> edges = edges_among(poses.size());
  edges.push_back(loop);
  const Eigen::Isometry3d revealed = (poses[loop.i].inverse() * poses[loop.j]).inverse() * loop.T_i_j;
  Loop result;
  result.matched_keyframe = found->keyframe;
  result.inliers = found->inliers;
  result.drift_m = revealed.translation().norm();
  result.drift_deg = Eigen::AngleAxisd(revealed.linear()).angle() * 180 / M_PI;
  tracking::PoseGraphResult solved = tracking::optimize_pose_graph(poses, edges, {0}, lc.graph);
  result.accepted = solved.accepted.back();
  std::vector<tracking::PoseGraphEdge> added = {loop};
  if (!result.accepted) {
    // Drift that came at once (a frame aligned to someone walking past) is confirmed by a second
    // detection revealing the same error, rejected or accepted; a look-alike place seldom
    // repeats its error.
    const auto recent = [&](const tracking::PoseGraphEdge& e) {
      return e.loop && e.j + static_cast<std::size_t>(lc.confirm_within) >= loop.j;
    };
    while (!rejected_loops_.empty() && !recent(rejected_loops_.front()))
      rejected_loops_.pop_front();
    std::vector<tracking::PoseGraphEdge> candidates(rejected_loops_.rbegin(),
                                                    rejected_loops_.rend());
    const std::size_t rejected = candidates.size();
    std::copy_if(edges.rbegin() + 1, edges.rend(), std::back_inserter(candidates), recent);
    for (std::size_t c = 0; c < candidates.size() && !result.accepted; ++c) {
      if (!tracking::loops_agree(poses, loop, candidates[c], lc.graph)) continue;
      added = {loop};
      added[0].confirmed = true;
      if (c < rejected) {  // the earlier one joins the graph with it
        added.insert(added.begin(), candidates[c]);
        added[0].confirmed = true;
      }
      std::vector<tracking::PoseGraphEdge> trial(edges.begin(), edges.end() - 1);
      trial.insert(trial.end(), added.begin(), added.end());
      tracking::PoseGraphResult again = tracking::optimize_pose_graph(poses, trial, {0}, lc.graph);
      if (!std::all_of(again.accepted.end() - static_cast<long>(added.size()), again.accepted.end(),
                       [](bool a) { return a; })) {
        continue;
      }
      result.accepted = true;
      result.confirms = candidates[c].j;
      solved = std::move(again);
      if (c < rejected) rejected_loops_.erase(rejected_loops_.end() - 1 - static_cast<long>(c));
    }
    if (!result.accepted) added = {loop}, rejected_loops_.push_back(loop);
  }
  if (result.accepted) {
    result.solved = std::move(solved.poses);
    std::lock_guard lock(graph_mutex_);
    edges_.insert(edges_.end(), added.begin(), added.end());
  }
  return result;
}

BackEnd::Linked BackEnd::link_covisible(const FrameTracker::PreparedKeyframe& keyframe,
                                        const tracking::OdometryConfig& odometry,
                                        const std::vector<Eigen::Isometry3d>& poses) {
  const int wanted = config_.loop_closure.covisible_keyframes;
  Linked linked;
  if (wanted <= 0 || !keyframe.frame) return linked;
  std::vector<tracking::PoseGraphEdge> edges = edges_among(poses.size());
  const tracking::PoseGraphConfig& graph = config_.loop_closure.graph;
  std::vector<tracking::PoseGraphEdge> added;
  // Only a blurred keyframe (blur_scale_px or more at the finest level): its reference edge is
  // then the weak link, colour lying under blur. A sharp keyframe is measured best by its
  // reference: on teddy the longer baselines' edges made sharp keyframes worse.
  const tracking::OdometryFrame::Level& finest = keyframe.frame->levels().back();
  const double blur_px = finest.fx * keyframe.angular_rate * odometry.exposure;
  const bool sharp = blur_px < odometry.blur_scale_px;
  for (const FrameTracker::PreparedKeyframe& earlier : sharp ? decltype(covisible_){} : covisible_) {
    const std::size_t i = earlier.keyframe, j = keyframe.keyframe;
    if (i >= j || std::any_of(edges.begin(), edges.end(), [&](const auto& e) { return e.i == i && e.j == j; })) continue;
    tracking::OdometryConfig weighted = odometry;
    weighted.depth_weight =
        tracking::blur_aware_depth_weight(odometry, *keyframe.frame, keyframe.angular_rate, earlier.angular_rate);
    const tracking::OdometryResult r =
        tracking::align_rgbd(*earlier.frame, *keyframe.frame, poses[j].inverse() * poses[i], weighted,
                             {earlier.twist, keyframe.twist});
    if (!r.converged) {
      ++linked.rejected;
      continue;
    }
    tracking::PoseGraphEdge edge;
    edge.i = i, edge.j = j;
    edge.T_i_j = r.T_cur_ref.inverse();
    // An alignment far from where the chain puts the pair found another minimum: left out.
    const Eigen::Isometry3d disagreement = (poses[i].inverse() * poses[j]).inverse() * edge.T_i_j;
    if (disagreement.translation().norm() > graph.drift_floor_m ||
        Eigen::AngleAxisd(disagreement.linear()).angle() * 180 / M_PI > graph.drift_floor_deg) {
      ++linked.rejected;
      continue;
    }
    edge.information = edge_information(r.information);
    added.push_back(edge);
  }
  covisible_.push_back(keyframe);
  // Its reference among them already has its edge: `wanted` besides it.
  while (covisible_.size() > static_cast<std::size_t>(wanted) + 1) covisible_.pop_front();
  linked.edges = added.size();
  if (added.empty()) return linked;
  edges.insert(edges.end(), added.begin(), added.end());
  std::size_t oldest = keyframe.keyframe;
  for (const FrameTracker::PreparedKeyframe& k : covisible_) oldest = std::min(oldest, k.keyframe);
  linked.solved = solve_window(poses, edges, oldest, graph);
  std::lock_guard lock(graph_mutex_);
  edges_.insert(edges_.end(), added.begin(), added.end());
  return linked;
}

BackEnd::State BackEnd::state() const {
  State s;
  {
    std::lock_guard lock(graph_mutex_);
    s.edges = edges_;
  }
  s.rejected_loops.assign(rejected_loops_.begin(), rejected_loops_.end());
  for (const FrameTracker::PreparedKeyframe& k : covisible_) {
    s.covisible.push_back(k.keyframe);
    s.covisible_rates.push_back(k.angular_rate);
    s.covisible_labels.push_back(k.labels);
    s.covisible_twists.push_back(twist_array(k.twist));
  }
  return s;
}

void BackEnd::restore(State s, std::size_t keyframes, const std::vector<std::size_t>& mapped,
                      const std::function<splat::RgbdFrame(std::size_t)>& keyframe,
                      const std::function<splat::RgbdFrame(std::size_t)>& mapped_keyframe) {
  auto inconsistent = [](const std::string& what) { throw splat::Error("SlamSystem::restore: " + what); };
  for (const auto* edges : {&s.edges, &s.rejected_loops}) {
    for (const tracking::PoseGraphEdge& e : *edges) {
      if (e.i >= keyframes || e.j >= keyframes)
        inconsistent("a pose graph edge names a keyframe that does not exist");
    }
  }
  rejected_loops_.assign(s.rejected_loops.begin(), s.rejected_loops.end());
  if (s.covisible.size() > static_cast<std::size_t>(config_.loop_closure.covisible_keyframes) + 1) {
    inconsistent(std::to_string(s.covisible.size()) +
                 " covisible keyframes, more than covisible_keyframes " +
                 std::to_string(config_.loop_closure.covisible_keyframes) + " + 1");
  }
  // Prepared as tracking prepared them, their moving regions left out.
  covisible_ =
      restore_prepared_keyframes(s.covisible, s.covisible_rates, s.covisible_labels, s.covisible_twists, keyframe,
                                 config_, "SlamSystem::restore: covisibility's keyframes");
  {
    std::lock_guard lock(places_mutex_);
    for (std::size_t k : mapped) {
      const splat::RgbdFrame frame = mapped_keyframe(k);
      places_.add(k, tracking::extract_place_features(frame, config_.loop_closure.places));
      thumbnails_.emplace_back(k, thumbnail(frame));
    }
  }
  std::lock_guard lock(graph_mutex_);
  edges_ = std::move(s.edges);
}

}  // namespace app

