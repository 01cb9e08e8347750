#include "slam/slam_config.h"

#include <algorithm>

#include "splat/field_check.h"

namespace app {

void SlamConfig::validate() const {
  const splat::FieldCheck check("");
  if (front_end != "odometry" && front_end != "render") check.fail("front_end", "\"odometry\" or \"render\"", "\"" + front_end + "\"");
  check.at_least("keyframe_render_iterations", keyframe_render_iterations, 0);
  check.at_least("recovery_keyframes", recovery_keyframes, 0);
  check.at_least("lost_residual_factor", lost_residual_factor, 1.0);
  check.in_range("keyframe_overlap", keyframe_overlap, 0.0, 1.0);
  check.at_least("keyframe_every", keyframe_every, 1);
  check.positive("keyframe_translation", keyframe_translation);
  check.positive("keyframe_rotation_deg", keyframe_rotation_deg);
  check.at_least("retry_warmup_iterations", retry_warmup_iterations, 0);
  check.at_least("refine_passes", refine_passes, 0);
  check.at_least("refine_iterations", refine_iterations, 0);
  check.at_least("refine_densify_passes", refine_densify_passes, 0);
  check.in_range("refine_blur_samples", refine_blur_samples, 1, 16);
  check.at_least("refine_max_visits", refine_max_visits, 0);
  check.at_least("refine_cache_mib", refine_cache_mib, 0.0);
  check.at_least("refine_coarse_passes", refine_coarse_passes, 0);
  check.positive("refine_coarse_learning_rate_scale", refine_coarse_learning_rate_scale);
  check.at_least("relocalize_iterations", relocalize_iterations, 0);
  check.at_least("mapping_backlog_mib", mapping_backlog_mib, 0.0);
  check.at_least("loop_closure.min_separation", loop_closure.min_separation, 1);
  check.at_least("loop_closure.dense_width", loop_closure.dense_width, 16);
  check.at_least("loop_closure.covisible_keyframes", loop_closure.covisible_keyframes, 0);
  const tracking::PlaceRecognitionConfig& p = loop_closure.places;
  check.at_least("loop_closure.features", p.features, 10);
  check.in_range("loop_closure.max_hamming", p.max_hamming, 0, 256);
  check.in_range("loop_closure.ratio", p.ratio, 0.0, 1.0);
  check.at_least("loop_closure.min_matches", p.min_matches, 3);
  check.at_least("loop_closure.min_inliers", p.min_inliers, 3);
  check.positive("loop_closure.inlier_distance", p.inlier_distance);
  check.at_least("loop_closure.ransac_iterations", p.ransac_iterations, 1);
  check.at_least("loop_closure.candidates", p.candidates, 1);
  const tracking::PoseGraphConfig& g = loop_closure.graph;
  check.at_least("loop_closure.max_iterations", g.max_iterations, 1);
  check.positive("loop_closure.loop_huber_sigmas", g.loop_huber_sigmas);
  check.at_least("loop_closure.odometry_huber_sigmas", g.odometry_huber_sigmas, 0.0);
  check.positive("loop_closure.drift_per_metre", g.drift_per_metre);
  check.positive("loop_closure.drift_deg_per_metre", g.drift_deg_per_metre);
  check.at_least("loop_closure.drift_floor_m", g.drift_floor_m, 0.0);
  check.at_least("loop_closure.drift_floor_deg", g.drift_floor_deg, 0.0);
  check.at_least("loop_closure.confirmed_budget_factor", g.confirmed_budget_factor, 1.0);
  check.at_least("loop_closure.confirm_within", loop_closure.confirm_within, 0);
  odometry.validate("odometry.");
  moving.validate("moving.");
  tracking.validate("tracking.");
  mapping.validate("mapping.");
}

SlamConfig::SweepVisits SlamConfig::sweep_visits(std::size_t frames) const {
  const auto passes = static_cast<std::size_t>(std::max(refine_passes, 0));
  SweepVisits v;
  const std::size_t densify_passes =
      std::min(passes, static_cast<std::size_t>(std::max(refine_densify_passes, 0)));
  v.densifying = frames * densify_passes;
  const auto cap = static_cast<std::size_t>(std::max(refine_max_visits, 0));
  v.total = v.densifying + std::min(frames * passes - v.densifying, cap > v.densifying ? cap - v.densifying : 0);
  // The coarse passes' share of the passes after the densifying ones, of the visits after them.
  const std::size_t later_passes = passes - densify_passes;
  const std::size_t coarse_passes =
      std::min(later_passes, static_cast<std::size_t>(std::max(refine_coarse_passes, 0)));
  if (later_passes > 0) v.coarse = (v.total - v.densifying) * coarse_passes / later_passes;
  return v;
}

}  // namespace app
