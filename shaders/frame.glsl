// Declarations the per-Gaussian stages share: the frame parameters (binding 0) and the map's
// parameter arrays (bindings 1..5), with loaders that mirror the CPU's.
#ifndef GSLAM_FRAME_GLSL
#define GSLAM_FRAME_GLSL
#extension GL_GOOGLE_include_directive : require
#include "shader_io.h"

#include "frame_params.glsl"
layout(std430, binding = 1) readonly buffer MeansBuffer { float means[]; };          // [N, 3]
layout(std430, binding = 2) readonly buffer LogScalesBuffer { float log_scales[]; }; // [N, 3]
layout(std430, binding = 3) readonly buffer RotationsBuffer { float rotations[]; };  // [N, 4]
layout(std430, binding = 4) readonly buffer OpacityBuffer { float opacity_logits[]; };  // [N]
layout(std430, binding = 5) readonly buffer ShBuffer { float sh[]; };                // [N, K, 3]

#include "splat_math.glsl"
#include "tile_box.glsl"

vec3 load_mean(uint i) { return vec3(means[3 * i], means[3 * i + 1], means[3 * i + 2]); }
vec3 load_log_scale(uint i) {
  return vec3(log_scales[3 * i], log_scales[3 * i + 1], log_scales[3 * i + 2]);
}
vec4 load_rotation(uint i) {
  return vec4(rotations[4 * i], rotations[4 * i + 1], rotations[4 * i + 2], rotations[4 * i + 3]);
}
float load_sh(uint i, int k, int c) { return sh[(i * frame.sh_stride + uint(k)) * 3u + uint(c)]; }

// W of p_cam = W p_world + t (the parameters hold it row-major; GLSL constructors take columns).
mat3 camera_rotation() {
  return transpose(mat3(frame.rotation[0], frame.rotation[1], frame.rotation[2], frame.rotation[3],
                        frame.rotation[4], frame.rotation[5], frame.rotation[6], frame.rotation[7],
                        frame.rotation[8]));
}
vec3 camera_translation() { return vec3(frame.translation[0], frame.translation[1], frame.translation[2]); }
vec3 camera_position() { return vec3(frame.cam_position[0], frame.cam_position[1], frame.cam_position[2]); }

int sh_coeff_count(int degree) { return (degree + 1) * (degree + 1); }

#endif  // GSLAM_FRAME_GLSL
