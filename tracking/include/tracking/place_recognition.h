// Place recognition for loop closure and relocalization: ORB features (OpenCV) of every
// keyframe with the 3D points their depth gives; a query frame is matched against the stored
// keyframes by descriptor, and each candidate verified geometrically: RANSAC over 3-point rigid
// fits of the matched 3D points, then a least-squares fit on the inliers, whose Gauss-Newton
// information the pose graph uses.
#pragma once
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Geometry>

#include "splat/rgbd_frame.h"

namespace tracking {

struct PlaceRecognitionConfig {
  int features = 500;          // ORB features per keyframe
  int max_hamming = 64;        // a descriptor match at most this far (of 256 bits)
  double ratio = 0.8;          // and clearly better than the second best (Lowe's ratio test)
  int min_matches = 30;        // a candidate needs this many matches to be verified
  int min_inliers = 25;        // and this many RANSAC inliers to be accepted
  double inlier_distance = 0.03;  // metres (3D point distance after the fit)
  int ransac_iterations = 300;
  int candidates = 3;          // keyframes verified per query, most matches first
};

// One frame's features: 3D points in its camera frame (only where depth was measured) and
// their 32-byte ORB descriptors.
struct PlaceFeatures {
  std::vector<Eigen::Vector3f> points;
  std::vector<std::array<uint8_t, 32>> descriptors;
};
PlaceFeatures extract_place_features(const splat::RgbdFrame& frame, const PlaceRecognitionConfig& config = {});

struct PlaceMatch {
  std::size_t keyframe = 0;            // the stored keyframe's id
  Eigen::Isometry3d T_keyframe_query;  // the query camera in the keyframe's camera frame
  int matches = 0, inliers = 0;
  double rms_m = 0;                    // inlier distance after the fit
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();  // se(3), translation first
};

class PlaceDatabase {
 public:
  explicit PlaceDatabase(const PlaceRecognitionConfig& config = {}) : config_(config) {}
  void add(std::size_t keyframe, PlaceFeatures features);
  std::size_t size() const { return entries_.size(); }
  // Verified matches of `query` among the stored keyframes that `eligible(id)` allows, best
  // (most inliers) first.
  template <typename Eligible>
  std::vector<PlaceMatch> query(const PlaceFeatures& query, Eligible eligible) const {
    std::vector<std::size_t> allowed;
    for (std::size_t e = 0; e < entries_.size(); ++e)
      if (eligible(entries_[e].keyframe)) allowed.push_back(e);
    return query_entries(query, allowed);
  }

 private:
  struct Entry {
    std::size_t keyframe;
    PlaceFeatures features;
  };
  std::vector<PlaceMatch> query_entries(const PlaceFeatures& query, const std::vector<std::size_t>& allowed) const;
  PlaceRecognitionConfig config_;
  std::vector<Entry> entries_;
};

// The rigid transform T with T * from[i] ~ to[i] for matched 3D points, by RANSAC then least
// squares on the inliers; nullopt where too few agree. Exposed for tests.
std::optional<PlaceMatch> fit_rigid_ransac(const std::vector<Eigen::Vector3f>& from, const std::vector<Eigen::Vector3f>& to,
                                           const PlaceRecognitionConfig& config, uint32_t seed = 1);

}  // namespace tracking
