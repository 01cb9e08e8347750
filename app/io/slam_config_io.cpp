#include "io/slam_config_io.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <variant>

#include "splat/error.h"

namespace app {
namespace {

// One configuration field: its key path in the JSON document and where it lives. Reading and
// writing both go through this one table, so what --print-config writes --config reads back.
using FieldRef = std::variant<int*, std::size_t*, uint32_t*, double*, bool*, std::vector<int>*, std::string*>;
struct Field {
  const char* section;  // "" for top-level keys
  const char* key;
  FieldRef ref;
};

std::vector<Field> fields(SlamConfig& c) {
  tracking::TrackingConfig& t = c.tracking;
  tracking::OdometryConfig& o = c.odometry;
  mapping::MapperConfig& m = c.mapping;
  return {
      {"", "front_end", &c.front_end},
      {"", "keyframe_render_iterations", &c.keyframe_render_iterations},
      {"", "recovery_keyframes", &c.recovery_keyframes},
      {"", "lost_residual_factor", &c.lost_residual_factor},
      {"", "keyframe_overlap", &c.keyframe_overlap},
      {"", "keyframe_every", &c.keyframe_every},
      {"", "keyframe_translation", &c.keyframe_translation},
      {"", "keyframe_rotation_deg", &c.keyframe_rotation_deg},
      {"", "retry_warmup_iterations", &c.retry_warmup_iterations},
      {"", "refine_passes", &c.refine_passes},
      {"", "refine_iterations", &c.refine_iterations},
      {"", "refine_max_visits", &c.refine_max_visits},
      {"", "refine_all_frames", &c.refine_all_frames},
      {"", "refine_coarse_passes", &c.refine_coarse_passes},
      {"", "refine_coarse_learning_rate_scale", &c.refine_coarse_learning_rate_scale},
      {"", "refine_densify_passes", &c.refine_densify_passes},
      {"", "refine_blur_samples", &c.refine_blur_samples},
      {"", "refine_cache_mib", &c.refine_cache_mib},
      {"", "relocalize_iterations", &c.relocalize_iterations},
      {"", "mapping_backlog_mib", &c.mapping_backlog_mib},
      {"", "overlap_mapping", &c.overlap_mapping},
      {"loop_closure", "enabled", &c.loop_closure.enabled},
      {"loop_closure", "min_separation", &c.loop_closure.min_separation},
      {"loop_closure", "dense_width", &c.loop_closure.dense_width},
      {"loop_closure", "covisible_keyframes", &c.loop_closure.covisible_keyframes},
      {"loop_closure", "confirm_within", &c.loop_closure.confirm_within},
      {"loop_closure", "features", &c.loop_closure.places.features},
      {"loop_closure", "max_hamming", &c.loop_closure.places.max_hamming},
      {"loop_closure", "ratio", &c.loop_closure.places.ratio},
      {"loop_closure", "min_matches", &c.loop_closure.places.min_matches},
      {"loop_closure", "min_inliers", &c.loop_closure.places.min_inliers},
      {"loop_closure", "inlier_distance", &c.loop_closure.places.inlier_distance},
      {"loop_closure", "ransac_iterations", &c.loop_closure.places.ransac_iterations},
      {"loop_closure", "candidates", &c.loop_closure.places.candidates},
      {"loop_closure", "max_iterations", &c.loop_closure.graph.max_iterations},
      {"loop_closure", "loop_huber_sigmas", &c.loop_closure.graph.loop_huber_sigmas},
      {"loop_closure", "odometry_huber_sigmas", &c.loop_closure.graph.odometry_huber_sigmas},
      {"loop_closure", "drift_per_metre", &c.loop_closure.graph.drift_per_metre},
      {"loop_closure", "drift_deg_per_metre", &c.loop_closure.graph.drift_deg_per_metre},
      {"loop_closure", "drift_floor_m", &c.loop_closure.graph.drift_floor_m},
      {"loop_closure", "drift_floor_deg", &c.loop_closure.graph.drift_floor_deg},
      {"loop_closure", "confirmed_budget_factor", &c.loop_closure.graph.confirmed_budget_factor},
      {"odometry", "iterations", &o.iterations},
      {"odometry", "finest_width", &o.finest_width},
      {"odometry", "max_points", &o.max_points},
      {"odometry", "depth_noise", &o.depth_noise},
      {"odometry", "t_dof", &o.t_dof},
      {"odometry", "depth_weight", &o.depth_weight},
      {"odometry", "rolling_shutter", &o.rolling_shutter},
      {"odometry", "blur_scale_px", &o.blur_scale_px},
      {"odometry", "exposure", &o.exposure},
      {"odometry", "estimate_exposure", &o.estimate_exposure},
      {"odometry", "estimate_brightness", &o.estimate_brightness},
      {"odometry", "fade_per_blur_px", &o.fade_per_blur_px},
      {"odometry", "exposure_window", &o.exposure_window},
      {"odometry", "min_depth", &o.min_depth},
      {"odometry", "max_depth", &o.max_depth},
      {"odometry", "max_depth_slope", &o.max_depth_slope},
      {"odometry", "min_step_translation", &o.min_step_translation},
      {"odometry", "min_step_rotation", &o.min_step_rotation},
      {"odometry", "min_overlap", &o.min_overlap},
      {"odometry", "min_conditioning", &o.min_conditioning},
      {"moving", "enabled", &c.moving.enabled},
      {"moving", "max_width", &c.moving.max_width},
      {"moving", "min_change", &c.moving.min_change},
      {"moving", "noise_sigmas", &c.moving.noise_sigmas},
      {"moving", "min_region", &c.moving.min_region},
      {"moving", "grow_px", &c.moving.grow_px},
      {"moving", "prior_grow_px", &c.moving.prior_grow_px},
      {"tracking", "pyramid", &t.pyramid},
      {"tracking", "iterations", &t.iterations},
      {"tracking", "warmup_iterations", &t.warmup_iterations},
      {"tracking", "warmup_step_translation", &t.warmup_step_translation},
      {"tracking", "warmup_step_rotation", &t.warmup_step_rotation},
      {"tracking", "depth_sigma", &t.depth_sigma},
      {"tracking", "color_sigma", &t.color_sigma},
      {"tracking", "color_weight", &t.color_weight},
      {"tracking", "color_max_factor", &t.color_max_factor},
      {"tracking", "huber", &t.huber},
      {"tracking", "alpha_threshold", &t.alpha_threshold},
      {"tracking", "outlier_factor", &t.outlier_factor},
      {"tracking", "min_step_translation", &t.min_step_translation},
      {"tracking", "min_step_rotation", &t.min_step_rotation},
      {"tracking", "min_overlap", &t.min_overlap},
      {"tracking", "max_median_residual", &t.max_median_residual},
      {"mapping", "resolution_factor", &m.resolution_factor},
      {"mapping", "refine_resolution_factor", &m.refine_resolution_factor},
      {"mapping", "iterations", &m.iterations},
      {"mapping", "window", &m.window},
      {"mapping", "max_keyframes", &m.max_keyframes},
      {"mapping", "color_weight", &m.color_weight},
      {"mapping", "ssim_weight", &m.ssim_weight},
      {"mapping", "depth_weight", &m.depth_weight},
      {"mapping", "refine_depth_weight", &m.refine_depth_weight},
      {"mapping", "depth_alpha_threshold", &m.depth_alpha_threshold},
      {"mapping", "refine_depth_alpha_threshold", &m.refine_depth_alpha_threshold},
      {"mapping", "refine_learning_rate_scale", &m.refine_learning_rate_scale},
      {"mapping", "refine_pose_learning_rate", &m.refine_pose_learning_rate},
      {"mapping", "refine_pose_rotation_learning_rate", &m.refine_pose_rotation_learning_rate},
      {"mapping", "refine_vignetting_rate", &m.refine_vignetting_rate},
      {"mapping", "isotropic", &m.isotropic},
      {"mapping", "device_resident", &m.device_resident},
      {"mapping", "sweep_device_cache_mib", &m.sweep_device_cache_mib},
      {"mapping", "densify_alpha", &m.densify_alpha},
      {"mapping", "depth_error_factor", &m.depth_error_factor},
      {"mapping", "refine_seed_depth_holes", &m.refine_seed_depth_holes},
      {"mapping", "seed_stride", &m.seed.stride},
      {"mapping", "seed_opacity", &m.seed.opacity},
      {"mapping", "seed_scale_factor", &m.seed.scale_factor},
      {"mapping", "sh_degree", &m.seed.sh_degree},
      {"mapping", "prune_opacity", &m.prune_opacity},
      {"mapping", "ghost_views", &m.ghost_views},
      {"mapping", "free_space_margin", &m.free_space_margin},
      {"mapping", "prune_max_scale", &m.prune_max_scale},
      {"mapping", "pose_learning_rate", &m.pose_learning_rate},
      {"mapping", "pose_rotation_learning_rate", &m.pose_rotation_learning_rate},
      {"mapping", "random_seed", &m.random_seed},
      {"mapping", "learning_rate_means", &m.adam.means},
      {"mapping", "learning_rate_log_scales", &m.adam.log_scales},
      {"mapping", "learning_rate_rotations", &m.adam.rotations},
      {"mapping", "learning_rate_opacity", &m.adam.opacity_logits},
      {"mapping", "learning_rate_sh_dc", &m.adam.sh_dc},
      {"mapping", "learning_rate_sh_rest", &m.adam.sh_rest},
  };
}

std::string path_of(const Field& f) { return *f.section ? std::string(f.section) + "." + f.key : std::string(f.key); }

[[noreturn]] void type_error(const std::string& path, const std::string& expected, const nlohmann::json& got) {
  throw splat::Error(path + ": expected " + expected + ", got " + got.dump());
}

// An integer in [lo, hi]: a JSON integer, or a number with no fractional part.
template <typename T>
T read_integer(const std::string& path, const nlohmann::json& v) {
  const double lo = static_cast<double>(std::numeric_limits<T>::min());
  const double hi = static_cast<double>(std::numeric_limits<T>::max());
  const std::string expected = "an integer in [" + std::to_string(std::numeric_limits<T>::min()) + ", " +
                               std::to_string(std::numeric_limits<T>::max()) + "]";
  if (!v.is_number() || v.is_boolean()) type_error(path, expected, v);
  if (v.is_number_unsigned()) {
    if (v.get<uint64_t>() > static_cast<uint64_t>(std::numeric_limits<T>::max())) type_error(path, expected, v);
    return static_cast<T>(v.get<uint64_t>());
  }
  if (v.is_number_integer()) {
    const int64_t x = v.get<int64_t>();
    if (static_cast<double>(x) < lo || static_cast<double>(x) > hi) type_error(path, expected, v);
    return static_cast<T>(x);
  }
  const double x = v.get<double>();
  if (!(x >= lo && x <= hi) || std::floor(x) != x) type_error(path, expected, v);
  return static_cast<T>(x);
}

void read_field(const Field& f, const nlohmann::json& v) {
  const std::string path = path_of(f);
  std::visit(
      [&](auto* target) {
        using T = std::remove_pointer_t<decltype(target)>;
        if constexpr (std::is_same_v<T, bool>) {
          if (!v.is_boolean()) type_error(path, "true or false", v);
          *target = v.get<bool>();
        } else if constexpr (std::is_same_v<T, double>) {
          if (!v.is_number() || !std::isfinite(v.get<double>())) type_error(path, "a finite number", v);
          *target = v.get<double>();
        } else if constexpr (std::is_same_v<T, std::string>) {
          if (!v.is_string()) type_error(path, "a string", v);
          *target = v.get<std::string>();
        } else if constexpr (std::is_same_v<T, std::vector<int>>) {
          if (!v.is_array()) type_error(path, "a list of integers", v);
          std::vector<int> list;
          for (std::size_t i = 0; i < v.size(); ++i) list.push_back(read_integer<int>(path + "[" + std::to_string(i) + "]", v[i]));
          *target = std::move(list);
        } else {
          *target = read_integer<T>(path, v);
        }
      },
      f.ref);
}

void read_section(const nlohmann::json& object, const std::string& section, const std::vector<Field>& table) {
  for (const auto& [key, value] : object.items()) {
    const std::string& name = key;  // a structured binding: clang 14 does not capture it
    const bool is_section = std::any_of(table.begin(), table.end(), [&](const Field& f) { return f.section == name; });
    if (section.empty() && is_section) {
      if (!value.is_object()) type_error(key, "an object of settings", value);
      read_section(value, key, table);
      continue;
    }
    const std::string path = section.empty() ? key : section + "." + key;
    bool known = false;
    for (const Field& f : table) {
      if (f.section == section && f.key == key) {
        read_field(f, value);
        known = true;
        break;
      }
    }
    if (!known) throw splat::Error(path + ": unknown setting (gslam reconstruct --print-config lists them all)");
  }
}

}  // namespace

SlamConfig slam_config_from_json(const nlohmann::json& document) {
  if (!document.is_object()) type_error("the configuration", "a JSON object of settings", document);
  SlamConfig config;
  read_section(document, "", fields(config));
  config.validate();
  return config;
}

nlohmann::json slam_config_to_json(const SlamConfig& config) {
  SlamConfig copy = config;
  nlohmann::json document = {
      {"odometry", nlohmann::json::object()}, {"tracking", nlohmann::json::object()}, {"mapping", nlohmann::json::object()}};
  for (const Field& f : fields(copy)) {
    nlohmann::json& section = *f.section ? document[f.section] : document;
    std::visit([&](auto* value) { section[f.key] = *value; }, f.ref);
  }
  return document;
}

SlamConfig load_slam_config(const std::filesystem::path& path) {
  if (path.empty()) return SlamConfig{};
  std::ifstream in(path);
  if (!in) throw splat::Error(path.string() + ": cannot open file");
  try {
    return slam_config_from_json(nlohmann::json::parse(in));
  } catch (const nlohmann::json::exception& e) {
    throw splat::Error(path.string() + ": " + e.what());
  } catch (const splat::Error& e) {
    throw splat::Error(path.string() + ": " + e.what());
  }
}

}  // namespace app
