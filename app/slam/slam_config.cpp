#include "slam/slam_config.h"

#include "splat/field_check.h"

namespace app {

void SlamConfig::validate() const {
  const splat::FieldCheck check("");
  if (front_end != "odometry" && front_end != "render") check.fail("front_end", "\"odometry\" or \"render\"", "\"" + front_end + "\"");
  check.at_least("keyframe_render_iterations", keyframe_render_iterations, 0);
  check.at_least("recovery_keyframes", recovery_keyframes, 0);
  check.in_range("keyframe_overlap", keyframe_overlap, 0.0, 1.0);
  check.at_least("keyframe_every", keyframe_every, 1);
  check.positive("keyframe_translation", keyframe_translation);
  check.positive("keyframe_rotation_deg", keyframe_rotation_deg);
  check.at_least("retry_warmup_iterations", retry_warmup_iterations, 0);
  check.at_least("refine_passes", refine_passes, 0);
  check.at_least("refine_iterations", refine_iterations, 0);
  check.at_least("refine_densify_passes", refine_densify_passes, 0);
  check.at_least("refine_cache_mib", refine_cache_mib, 0.0);
  check.at_least("relocalize_iterations", relocalize_iterations, 0);
  odometry.validate("odometry.");
  tracking.validate("tracking.");
  mapping.validate("mapping.");
}

}  // namespace app
