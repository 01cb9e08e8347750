// The per-frame parameters every splat stage reads, at binding 0.
#ifndef GSLAM_FRAME_PARAMS_GLSL
#define GSLAM_FRAME_PARAMS_GLSL
#extension GL_GOOGLE_include_directive : require
#include "shader_io.h"

layout(std430, binding = 0) readonly buffer FrameBuffer { FrameParams frame; };

#endif  // GSLAM_FRAME_PARAMS_GLSL
