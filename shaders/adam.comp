#version 450
// One Adam step of the resident map, one invocation per Gaussian, from project_backward.comp's
// gradients: the same update as splat::adam_update (the moments first, then the parameter),
// in float where the CPU computes in double, with this Gaussian's own step count.
#extension GL_GOOGLE_include_directive : require
#include "shader_io.h"

layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Params { AdamParams adam; };
layout(std430, binding = 1) buffer Means { float means[]; };            // [N, 3]
layout(std430, binding = 2) buffer LogScales { float log_scales[]; };   // [N, 3]
layout(std430, binding = 3) buffer Rotations { float rotations[]; };    // [N, 4]
layout(std430, binding = 4) buffer Opacity { float opacity_logits[]; }; // [N]
layout(std430, binding = 5) buffer Sh { float sh[]; };                  // [N, K, 3]
layout(std430, binding = 6) readonly buffer DParams { float d_params[]; };  // [N, 11]
layout(std430, binding = 7) readonly buffer DSh { float d_sh[]; };          // [N, K, 3]
layout(std430, binding = 8) buffer MParams { float m_params[]; };  // [N, 11]
layout(std430, binding = 9) buffer VParams { float v_params[]; };  // [N, 11]
layout(std430, binding = 10) buffer MSh { float m_sh[]; };         // [N, K, 3]
layout(std430, binding = 11) buffer VSh { float v_sh[]; };         // [N, K, 3]
layout(std430, binding = 12) buffer Steps { uint steps[]; };       // [N]

float bias1, bias2;

// base^e by squaring, in double: GLSL has no double pow.
double power(double base, uint e) {
  double result = 1.0lf;
  for (; e != 0u; e >>= 1u) {
    if ((e & 1u) != 0u) result *= base;
    base *= base;
  }
  return result;
}

// Updates the moments m, v with gradient g and returns the parameter's step.
float update(inout float m, inout float v, float g, float lr) {
  float beta1 = float(adam.beta1), beta2 = float(adam.beta2);
  m = beta1 * m + (1.0 - beta1) * g;
  v = beta2 * v + (1.0 - beta2) * g * g;
  return lr * (m / bias1) / (sqrt(v / bias2) + adam.eps);
}

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= adam.count) return;
  uint t = steps[i] + 1u;
  steps[i] = t;
  bias1 = float(1.0lf - power(adam.beta1, t));
  bias2 = float(1.0lf - power(adam.beta2, t));

  float g[kGeometryFloats];
  for (uint k = 0u; k < kGeometryFloats; ++k) g[k] = d_params[i * kGeometryFloats + k];
  if (adam.isotropic != 0u) {
    float mean = (g[3] + g[4] + g[5]) / 3.0;
    g[3] = mean;
    g[4] = mean;
    g[5] = mean;
    for (uint k = 6u; k < 10u; ++k) g[k] = 0.0;
  }
  for (uint k = 0u; k < kGeometryFloats; ++k) {
    uint j = i * kGeometryFloats + k;
    float m = m_params[j], v = v_params[j];
    float lr = k < 3u ? adam.lr_means : (k < 6u ? adam.lr_log_scales : (k < 10u ? adam.lr_rotations : adam.lr_opacity));
    float step = update(m, v, g[k], lr);
    m_params[j] = m;
    v_params[j] = v;
    if (k < 3u) means[i * 3u + k] -= step;
    else if (k < 6u) log_scales[i * 3u + k - 3u] -= step;
    else if (k < 10u) rotations[i * 4u + k - 6u] -= step;
    else opacity_logits[i] -= step;
  }
  for (uint k = 0u; k < adam.sh_floats; ++k) {
    uint j = i * adam.sh_floats + k;
    float m = m_sh[j], v = v_sh[j];
    sh[j] -= update(m, v, d_sh[j], k < 3u ? adam.lr_sh_dc : adam.lr_sh_rest);
    m_sh[j] = m;
    v_sh[j] = v;
  }
}
