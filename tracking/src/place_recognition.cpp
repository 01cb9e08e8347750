#include "tracking/place_recognition.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <random>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

namespace tracking {
namespace {

int hamming(const std::array<uint8_t, 32>& a, const std::array<uint8_t, 32>& b) {
  int d = 0;
  for (int w = 0; w < 4; ++w) {
    uint64_t x, y;
    std::memcpy(&x, a.data() + 8 * w, 8);
    std::memcpy(&y, b.data() + 8 * w, 8);
    d += std::popcount(x ^ y);
  }
  return d;
}

// Rigid transform (no scale) taking from[i] onto to[i] for the listed indices.
Eigen::Isometry3d rigid_fit(const std::vector<Eigen::Vector3f>& from, const std::vector<Eigen::Vector3f>& to,
                            const std::vector<int>& indices) {
  Eigen::Matrix3Xd a(3, indices.size()), b(3, indices.size());
  for (std::size_t k = 0; k < indices.size(); ++k) {
    a.col(static_cast<Eigen::Index>(k)) = from[static_cast<std::size_t>(indices[k])].cast<double>();
    b.col(static_cast<Eigen::Index>(k)) = to[static_cast<std::size_t>(indices[k])].cast<double>();
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.matrix() = Eigen::umeyama(a, b, false);
  return T;
}

}  // namespace

PlaceFeatures extract_place_features(const splat::RgbdFrame& frame, const PlaceRecognitionConfig& config) {
  const int w = frame.width(), h = frame.height();
  cv::Mat grey(h, w, CV_8UC1);
  for (int y = 0; y < h; ++y) {
    auto* row = grey.ptr<uint8_t>(y);
    for (int x = 0; x < w; ++x) {
      const float* p = &frame.rgb[(static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)) * 3];
      const float v = 0.299f * p[0] + 0.587f * p[1] + 0.114f * p[2];
      row[x] = static_cast<uint8_t>(std::lround(std::clamp(v, 0.f, 1.f) * 255.f));
    }
  }
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  cv::ORB::create(config.features)->detectAndCompute(grey, cv::noArray(), keypoints, descriptors);
  PlaceFeatures f;
  const splat::Camera& k = frame.camera;
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const int u = static_cast<int>(std::lround(keypoints[i].pt.x)), v = static_cast<int>(std::lround(keypoints[i].pt.y));
    if (u < 0 || v < 0 || u >= w || v >= h) continue;
    const float z = frame.depth[static_cast<std::size_t>(v) * static_cast<std::size_t>(w) + static_cast<std::size_t>(u)];
    if (!(z > 0) || !std::isfinite(z)) continue;
    // OpenCV puts pixel centres at integers, the camera model at +0.5.
    const double x = (keypoints[i].pt.x + 0.5 - k.cx) / k.fx, y = (keypoints[i].pt.y + 0.5 - k.cy) / k.fy;
    f.points.emplace_back(static_cast<float>(x * z), static_cast<float>(y * z), z);
    std::array<uint8_t, 32> d;
    std::memcpy(d.data(), descriptors.ptr<uint8_t>(static_cast<int>(i)), 32);
    f.descriptors.push_back(d);
  }
  return f;
}

std::optional<PlaceMatch> fit_rigid_ransac(const std::vector<Eigen::Vector3f>& from, const std::vector<Eigen::Vector3f>& to,
                                           const PlaceRecognitionConfig& config, uint32_t seed) {
  const int n = static_cast<int>(from.size());
  if (n < 3 || n != static_cast<int>(to.size())) return std::nullopt;
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> pick(0, n - 1);
  const double threshold2 = config.inlier_distance * config.inlier_distance;
  auto inliers_of = [&](const Eigen::Isometry3d& T) {
    std::vector<int> in;
    for (int i = 0; i < n; ++i) {
      if ((T * from[static_cast<std::size_t>(i)].cast<double>() - to[static_cast<std::size_t>(i)].cast<double>()).squaredNorm() < threshold2) {
        in.push_back(i);
      }
    }
    return in;
  };
  std::vector<int> best;
  for (int it = 0; it < config.ransac_iterations; ++it) {
    const int a = pick(rng), b = pick(rng), c = pick(rng);
    if (a == b || b == c || a == c) continue;
    // A sample of nearly collinear points fixes no rotation.
    const Eigen::Vector3f ab = from[static_cast<std::size_t>(b)] - from[static_cast<std::size_t>(a)];
    const Eigen::Vector3f ac = from[static_cast<std::size_t>(c)] - from[static_cast<std::size_t>(a)];
    if (ab.cross(ac).norm() < 1e-4f) continue;
    std::vector<int> in = inliers_of(rigid_fit(from, to, {a, b, c}));
    if (in.size() > best.size()) best = std::move(in);
  }
  if (static_cast<int>(best.size()) < config.min_inliers) return std::nullopt;
  Eigen::Isometry3d T = rigid_fit(from, to, best);
  best = inliers_of(T);  // once more with the least-squares fit
  if (static_cast<int>(best.size()) < config.min_inliers) return std::nullopt;
  T = rigid_fit(from, to, best);
  PlaceMatch m;
  m.matches = n;
  m.inliers = static_cast<int>(best.size());
  // Gauss-Newton information of the fit (left perturbation of T, translation first), with the
  // residuals' own variance per coordinate.
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  double sum2 = 0;
  for (int i : best) {
    const Eigen::Vector3d p = T * from[static_cast<std::size_t>(i)].cast<double>();
    sum2 += (p - to[static_cast<std::size_t>(i)].cast<double>()).squaredNorm();
    Eigen::Matrix<double, 3, 6> J;
    J.leftCols<3>().setIdentity();
    J.rightCols<3>() << 0, p.z(), -p.y(), -p.z(), 0, p.x(), p.y(), -p.x(), 0;  // -[p]x
    H += J.transpose() * J;
  }
  m.rms_m = std::sqrt(sum2 / static_cast<double>(best.size()));
  const double variance = std::max(sum2 / (3.0 * static_cast<double>(best.size())), 1e-8);
  m.information = H / variance;
  m.T_keyframe_query = T;  // filled by the caller's convention (see PlaceDatabase)
  return m;
}

void PlaceDatabase::add(std::size_t keyframe, PlaceFeatures features) {
  entries_.push_back({keyframe, std::move(features)});
}

std::vector<PlaceMatch> PlaceDatabase::query_entries(const PlaceFeatures& query, const std::vector<std::size_t>& allowed) const {
  // Descriptor matches per allowed keyframe: (query index, keyframe index), ratio-tested.
  struct Candidate {
    std::size_t entry;
    std::vector<std::pair<int, int>> matches;
  };
  std::vector<Candidate> candidates;
  for (std::size_t e : allowed) {
    const PlaceFeatures& stored = entries_[e].features;
    Candidate c{e, {}};
    for (std::size_t q = 0; q < query.descriptors.size(); ++q) {
      int best = 257, second = 257, best_index = -1;
      for (std::size_t s = 0; s < stored.descriptors.size(); ++s) {
        const int d = hamming(query.descriptors[q], stored.descriptors[s]);
        if (d < best) second = best, best = d, best_index = static_cast<int>(s);
        else if (d < second) second = d;
      }
      if (best_index >= 0 && best <= config_.max_hamming && best < config_.ratio * second) {
        c.matches.emplace_back(static_cast<int>(q), best_index);
      }
    }
    if (static_cast<int>(c.matches.size()) >= config_.min_matches) candidates.push_back(std::move(c));
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& a, const Candidate& b) { return a.matches.size() > b.matches.size(); });
  if (candidates.size() > static_cast<std::size_t>(config_.candidates)) candidates.resize(static_cast<std::size_t>(config_.candidates));
  std::vector<PlaceMatch> verified;
  for (const Candidate& c : candidates) {
    std::vector<Eigen::Vector3f> from, to;  // keyframe points -> query points
    for (const auto& [q, s] : c.matches) {
      from.push_back(entries_[c.entry].features.points[static_cast<std::size_t>(s)]);
      to.push_back(query.points[static_cast<std::size_t>(q)]);
    }
    std::optional<PlaceMatch> m = fit_rigid_ransac(from, to, config_, static_cast<uint32_t>(c.entry + 1));
    if (!m) continue;
    // The fit is T_query_keyframe with the information of its left perturbation: that is the
    // information of T_keyframe_query's right perturbation, the pose graph's convention.
    m->T_keyframe_query = m->T_keyframe_query.inverse();
    m->keyframe = entries_[c.entry].keyframe;
    verified.push_back(*m);
  }
  std::sort(verified.begin(), verified.end(), [](const PlaceMatch& a, const PlaceMatch& b) { return a.inliers > b.inliers; });
  return verified;
}

}  // namespace tracking
