#include "app/slam_config_io.h"

#include <fstream>
#include <nlohmann/json.hpp>

#include "splat/error.h"

namespace app {

SlamConfig load_slam_config(const std::filesystem::path& path) {
  SlamConfig c;
  if (path.empty()) return c;
  std::ifstream in(path);
  if (!in) throw splat::Error(path.string() + ": cannot open file");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
    auto get = [](const nlohmann::json& obj, const char* key, auto& value) {
      if (obj.contains(key)) value = obj.at(key).get<std::decay_t<decltype(value)>>();
    };
    get(j, "keyframe_every", c.keyframe_every);
    get(j, "keyframe_translation", c.keyframe_translation);
    get(j, "keyframe_rotation_deg", c.keyframe_rotation_deg);
    get(j, "refine_passes", c.refine_passes);
    get(j, "refine_iterations", c.refine_iterations);
    get(j, "refine_all_frames", c.refine_all_frames);
    get(j, "refine_densify_passes", c.refine_densify_passes);
    get(j, "refine_cache_mib", c.refine_cache_mib);
    get(j, "relocalize_iterations", c.relocalize_iterations);
    if (j.contains("tracking")) {
      const auto& t = j.at("tracking");
      get(t, "pyramid", c.tracking.pyramid);
      get(t, "iterations", c.tracking.iterations);
      get(t, "depth_sigma", c.tracking.depth_sigma);
      get(t, "color_sigma", c.tracking.color_sigma);
      get(t, "color_weight", c.tracking.color_weight);
      get(t, "color_max_factor", c.tracking.color_max_factor);
      get(t, "alpha_threshold", c.tracking.alpha_threshold);
      get(t, "min_step_translation", c.tracking.min_step_translation);
      get(t, "min_step_rotation", c.tracking.min_step_rotation);
    }
    if (j.contains("mapping")) {
      const auto& m = j.at("mapping");
      get(m, "iterations", c.mapping.iterations);
      get(m, "window", c.mapping.window);
      get(m, "resolution_factor", c.mapping.resolution_factor);
      get(m, "refine_resolution_factor", c.mapping.refine_resolution_factor);
      get(m, "seed_stride", c.mapping.seed.stride);
      get(m, "seed_scale_factor", c.mapping.seed.scale_factor);
      get(m, "sh_degree", c.mapping.seed.sh_degree);
      get(m, "color_weight", c.mapping.color_weight);
      get(m, "ssim_weight", c.mapping.ssim_weight);
      get(m, "depth_weight", c.mapping.depth_weight);
      get(m, "refine_depth_weight", c.mapping.refine_depth_weight);
      get(m, "densify_alpha", c.mapping.densify_alpha);
      get(m, "refine_seed_depth_holes", c.mapping.refine_seed_depth_holes);
      get(m, "prune_max_scale", c.mapping.prune_max_scale);
      get(m, "isotropic", c.mapping.isotropic);
      get(m, "pose_learning_rate", c.mapping.pose_learning_rate);
      get(m, "pose_rotation_learning_rate", c.mapping.pose_rotation_learning_rate);
      get(m, "depth_alpha_threshold", c.mapping.depth_alpha_threshold);
      get(m, "refine_depth_alpha_threshold", c.mapping.refine_depth_alpha_threshold);
      get(m, "refine_learning_rate_scale", c.mapping.refine_learning_rate_scale);
      get(m, "refine_pose_rate_scale", c.mapping.refine_pose_rate_scale);
      get(m, "refine_vignetting_rate", c.mapping.refine_vignetting_rate);
    }
  } catch (const nlohmann::json::exception& e) {
    throw splat::Error(path.string() + ": " + e.what());
  }
  if (c.refine_passes < 0 || c.refine_iterations < 0 || c.refine_densify_passes < 0 || !(c.refine_cache_mib >= 0)) {
    throw splat::Error(path.string() + ": refine_passes, refine_iterations, refine_densify_passes and refine_cache_mib must be >= 0");
  }
  c.tracking.validate();
  c.mapping.validate();
  return c;
}

}  // namespace app
