#version 450
// Projection: one invocation per Gaussian, 1D workgroups of kGroupSize. Writes its 2D mean,
// conic, depth, radii, colour, opacity, cull reason, how many tiles its extent box touches,
// and its depth sort key (float bits; culled splats get 0xffffffff and no tiles).
// Reads bindings 0..5 (frame.glsl). Deterministic.
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"

layout(local_size_x = 256) in;
layout(std430, binding = 6) writeonly buffer Means2d { float means2d[]; };   // [N, 2]
layout(std430, binding = 7) writeonly buffer Conics { float conics[]; };     // [N, 3]
layout(std430, binding = 8) writeonly buffer Depths { float depths[]; };     // [N]
layout(std430, binding = 9) writeonly buffer Radii { int radii[]; };         // [N, 2]
layout(std430, binding = 10) writeonly buffer Colors { float colors[]; };    // [N, 3]
layout(std430, binding = 11) writeonly buffer Opacities { float opacities[]; };  // [N]
layout(std430, binding = 12) writeonly buffer TileCounts { uint tile_counts[]; };  // [N]
layout(std430, binding = 13) writeonly buffer DepthKeys { uint depth_keys[]; };    // [N]
layout(std430, binding = 14) writeonly buffer SortIds { uint sort_ids[]; };        // [N] = i
layout(std430, binding = 15) writeonly buffer Cull { uint cull[]; };               // [N]

void culled(uint i, uint reason) {
  cull[i] = reason;
  means2d[2 * i] = 0; means2d[2 * i + 1] = 0;
  conics[3 * i] = 0; conics[3 * i + 1] = 0; conics[3 * i + 2] = 0;
  radii[2 * i] = 0; radii[2 * i + 1] = 0;
  tile_counts[i] = 0;
  depth_keys[i] = 0xffffffffu;
}

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= frame.count) return;
  sort_ids[i] = i;
  mat3 w = camera_rotation();
  vec3 p_world = load_mean(i);
  vec3 p = transform_point(w, camera_translation(), p_world);
  float opacity = sigmoid(opacity_logits[i]);
  opacities[i] = opacity;
  depths[i] = p.z;

  // Colour for this view: SH at the unit direction from the camera, +0.5, clamped at 0.
  vec3 dir = p_world - camera_position();
  float dir_len = length(dir);
  float basis[16];
  sh_basis(dir_len > 0 ? frame.sh_degree : 0, dir_len > 0 ? dir / dir_len : dir, basis);
  int used = dir_len > 0 ? sh_coeff_count(frame.sh_degree) : 1;
  for (int c = 0; c < 3; ++c) {
    float sum = 0;
    for (int k = 0; k < used; ++k) sum += basis[k] * load_sh(i, k, c);
    colors[3 * i + c] = max(sum + 0.5, 0.0);
  }

  if (p.z < frame.near_z || p.z > frame.far_z) { culled(i, kCullDepth); return; }
  vec4 q = load_rotation(i);
  float q_len = length(q);
  if (!(q_len > 0)) { culled(i, kCullDegenerate); return; }
  // EWA: Sigma_cam = W Sigma W^T, cov2d = J Sigma_cam J^T + dilation.
  mat3 sigma = covariance_3d(q / q_len, load_log_scale(i));
  mat3 sigma_cam = w * sigma * transpose(w);
  mat2 cov2d = project_cov(p, sigma_cam);
  cov2d[0][0] += kCov2dDilation;
  cov2d[1][1] += kCov2dDilation;
  vec3 conic;
  if (!invert_sym2(cov2d, conic)) { culled(i, kCullDegenerate); return; }
  if (opacity < kAlphaMin) { culled(i, kCullFaint); return; }
  // Extent: where opacity * exp(-r^2/2) falls to kAlphaMin, at most kExtentSigmaMax sigma.
  float extend = min(kExtentSigmaMax, sqrt(2 * log(opacity / kAlphaMin)));
  float radius_x = ceil(extend * sqrt(cov2d[0][0]));
  float radius_y = ceil(extend * sqrt(cov2d[1][1]));
  vec2 mean2d = project_mean(p);
  if ((radius_x <= 0 && radius_y <= 0) || mean2d.x + radius_x <= 0 ||
      mean2d.x - radius_x >= float(frame.width) || mean2d.y + radius_y <= 0 ||
      mean2d.y - radius_y >= float(frame.height)) {
    { culled(i, kCullOffscreen); return; }
  }
  cull[i] = kCullNone;
  means2d[2 * i] = mean2d.x;
  means2d[2 * i + 1] = mean2d.y;
  conics[3 * i] = conic[0]; conics[3 * i + 1] = conic[1]; conics[3 * i + 2] = conic[2];
  radii[2 * i] = int(radius_x);
  radii[2 * i + 1] = int(radius_y);
  // Tiles touched by the per-axis extent box, clamped to the grid (as tile_box on the CPU).
  uvec2 lo, hi;
  tile_box(mean2d, ivec2(radius_x, radius_y), lo, hi);
  tile_counts[i] = (hi.x - lo.x) * (hi.y - lo.y);
  depth_keys[i] = floatBitsToUint(p.z);  // positive, so the bits order like the value
}
