// What the mapping-loss stages share: their parameters (binding 0) and the vignetting gain of a
// pixel, computed in double as mapping::Vignetting does before it casts the gain to float.
#ifndef GSLAM_LOSS_PIXEL_GLSL
#define GSLAM_LOSS_PIXEL_GLSL
#extension GL_GOOGLE_include_directive : require
#include "shader_io.h"

layout(std430, binding = 0) readonly buffer LossParamsBuffer { LossParams params; };

uint pixel_count() { return params.width * params.height; }

// r^2 = u^2 + v^2 at the centre of pixel p, u = (x + 0.5 - cx) / fx, v = (y + 0.5 - cy) / fy.
double radius2(uint p) {
  double u = (double(p % params.width) + 0.5lf - params.cx) / params.fx;
  double v = (double(p / params.width) + 0.5lf - params.cy) / params.fy;
  return u * u + v * v;
}

float vignetting_gain(double r2) { return float(1.0lf + r2 * (params.k1 + r2 * params.k2)); }

float sign_of(double r) { return r > 0.0lf ? 1.0 : (r < 0.0lf ? -1.0 : 0.0); }

#endif  // GSLAM_LOSS_PIXEL_GLSL
