#include "slam/slam_config.h"

#include "splat/field_check.h"

namespace app {

void SlamConfig::validate() const {
  const splat::FieldCheck check("");
  check.at_least("keyframe_every", keyframe_every, 1);
  check.positive("keyframe_translation", keyframe_translation);
  check.positive("keyframe_rotation_deg", keyframe_rotation_deg);
  check.at_least("retry_warmup_iterations", retry_warmup_iterations, 0);
  check.at_least("refine_passes", refine_passes, 0);
  check.at_least("refine_iterations", refine_iterations, 0);
  check.at_least("refine_densify_passes", refine_densify_passes, 0);
  check.at_least("refine_cache_mib", refine_cache_mib, 0.0);
  check.at_least("relocalize_iterations", relocalize_iterations, 0);
  tracking.validate("tracking.");
  mapping.validate("mapping.");
}

}  // namespace app
