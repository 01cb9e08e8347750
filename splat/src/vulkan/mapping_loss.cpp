// The mapping loss on the device: pointwise terms -> (D-SSIM: blur the statistics along rows,
// then columns -> SSIM terms -> blur their gradients back) -> gradient through the vignetting.
// Every stage writes its per-workgroup partial sums into one [groups, kLossPartials] buffer of
// doubles, added on the device in a fixed order (partials_sum.comp): kLossPartials values come back.
#include "vulkan/mapping_loss.h"

#include <cmath>
#include <cstddef>
#include <string>

#include "loss_blur_spv.h"
#include "loss_finish_spv.h"
#include "loss_pointwise_spv.h"
#include "loss_ssim_spv.h"
#include "partials_sum_spv.h"
#include "shader_io.h"
#include "splat/error.h"

namespace splat::vk {
namespace {

static_assert(sizeof(io::LossParams) == 136, "LossParams must match its std430 layout");

// The D-SSIM window exactly as losses.cpp builds Window<float>: taps in double, normalized,
// then rounded to float.
void window_taps(float (&taps)[io::kSsimTaps]) {
  constexpr int r = static_cast<int>(io::kSsimRadius);
  double raw[io::kSsimTaps], sum = 0;
  for (int i = -r; i <= r; ++i) sum += raw[i + r] = std::exp(-i * i / (2 * 1.5 * 1.5));
  for (int i = 0; i <= 2 * r; ++i) taps[i] = static_cast<float>(raw[i] / sum);
}

void check_buffer(const Buffer* buffer, const char* name, std::size_t bytes) {
  if (!buffer) throw Error(std::string("MappingLossKernels::record: no ") + name + " buffer");
  if (buffer->capacity() < bytes) {
    throw Error(std::string("MappingLossKernels::record: ") + name + " holds " +
                std::to_string(buffer->capacity()) + " bytes, expected at least " +
                std::to_string(bytes));
  }
}

}  // namespace

struct MappingLossKernels::Impl {
  explicit Impl(Context& c)
      : pointwise(c, kLossPointwiseSpv, 12, "loss_pointwise"),
        blur(c, kLossBlurSpv, 3, "loss_blur"),
        ssim(c, kLossSsimSpv, 4, "loss_ssim"),
        finish(c, kLossFinishSpv, 7, "loss_finish"),
        sum(c, kPartialsSumSpv, 2, "partials_sum"),
        params(c),
        planes{Buffer(c), Buffer(c), Buffer(c)},
        partials(c),
        sums(c) {}

  Kernel pointwise, blur, ssim, finish, sum;
  Buffer params;
  // D-SSIM scratch, [3 * kSsimStats, H, W] each: the statistics (later the SSIM gradient), the
  // row-blurred planes, and the fully blurred planes.
  Buffer planes[3];
  Buffer partials, sums;
  double host_sums[io::kLossPartials] = {};  // filled by the batch's run()
  // What result() weighs the partial sums with, from the last record().
  double color_scale = 0, depth_scale = 0, ssim_scale = 0;
  bool ssim_on = false;
};

MappingLossKernels::MappingLossKernels(Context& context) : impl_(std::make_shared<Impl>(context)) {}

void MappingLossKernels::record(CommandBatch& batch, const LossBuffers& buffers,
                                const Camera& camera, const MappingLoss& loss,
                                std::size_t measured) {
  camera.validate("MappingLossKernels::record");
  const std::size_t pixels = std::size_t(camera.width) * std::size_t(camera.height);
  const std::size_t groups = (pixels + io::kGroupSize - 1) / io::kGroupSize;
  // Vulkan guarantees 65535 workgroups per dimension; the stages dispatch pixels along x.
  if (groups > 65535) {
    throw Error("MappingLossKernels::record: " + std::to_string(pixels) + " pixels, at most " +
                std::to_string(65535 * io::kGroupSize));
  }
  if (measured > pixels) {
    throw Error("MappingLossKernels::record: " + std::to_string(measured) +
                " measured pixels in an image of " + std::to_string(pixels));
  }
  check_buffer(buffers.rgb, "rgb", pixels * 12);
  check_buffer(buffers.alpha, "alpha", pixels * 4);
  check_buffer(buffers.depth, "depth", pixels * 4);
  check_buffer(buffers.target_rgb, "target_rgb", pixels * 12);
  check_buffer(buffers.target_depth, "target_depth", pixels * 4);
  if (buffers.ignore) check_buffer(buffers.ignore, "ignore", pixels * 4);
  check_buffer(buffers.d_rgb, "d_rgb", pixels * 12);
  check_buffer(buffers.d_alpha, "d_alpha", pixels * 4);
  check_buffer(buffers.d_depth, "d_depth", pixels * 4);

  Impl& s = *impl_;
  const double values = 3.0 * static_cast<double>(pixels);
  s.color_scale = loss.color_weight / values;
  s.depth_scale = measured > 0 ? loss.depth_weight / static_cast<double>(measured) : 0.0;
  s.ssim_scale = loss.ssim_weight / values;
  s.ssim_on = loss.ssim_weight != 0;

  io::LossParams p{};
  p.fx = camera.fx;
  p.fy = camera.fy;
  p.cx = camera.cx;
  p.cy = camera.cy;
  p.k1 = loss.vignetting_k1;
  p.k2 = loss.vignetting_k2;
  p.color_scale = s.color_scale;
  p.depth_scale = s.depth_scale;
  p.alpha_threshold = loss.depth_alpha_threshold;
  p.ssim_scale = static_cast<float>(s.ssim_scale);
  window_taps(p.taps);
  p.width = static_cast<uint32_t>(camera.width);
  p.height = static_cast<uint32_t>(camera.height);
  p.has_ignore = buffers.ignore ? 1u : 0u;
  p.ssim = s.ssim_on ? 1u : 0u;

  // Reserve everything before recording: growing a buffer discards it.
  s.params.reserve(sizeof(p));
  // Without D-SSIM the planes are bound but not used: the smallest allocation.
  const std::size_t plane_bytes = s.ssim_on ? pixels * 3 * io::kSsimStats * 4 : 4;
  for (Buffer& b : s.planes) b.reserve(plane_bytes);
  s.partials.reserve(groups * io::kLossPartials * sizeof(double));
  s.sums.reserve(io::kLossPartials * sizeof(double));
  batch.upload(s.params, &p, sizeof(p));

  // Unused bindings still need a buffer: the ignore mask's stand-in is never read.
  const Buffer* ignore = buffers.ignore ? buffers.ignore : buffers.target_depth;
  const auto g = static_cast<uint32_t>(groups);
  batch.dispatch(s.pointwise,
                 {&s.params, buffers.rgb, buffers.alpha, buffers.depth, buffers.target_rgb,
                  buffers.target_depth, ignore, buffers.d_rgb, buffers.d_alpha, buffers.d_depth,
                  &s.planes[0], &s.partials},
                 {}, g);
  if (s.ssim_on) {
    // Statistics: planes[0] -> rows -> planes[1] -> columns -> planes[2].
    batch.dispatch(s.blur, {&s.params, &s.planes[0], &s.planes[1]}, {0u}, g, 3 * io::kSsimStats);
    batch.dispatch(s.blur, {&s.params, &s.planes[1], &s.planes[2]}, {1u}, g, 3 * io::kSsimStats);
    batch.dispatch(s.ssim, {&s.params, &s.planes[2], &s.planes[0], &s.partials}, {}, g);
    // The SSIM gradient through the (self-adjoint) blur, the same way round.
    batch.dispatch(s.blur, {&s.params, &s.planes[0], &s.planes[1]}, {0u}, g, 3 * io::kSsimGrads);
    batch.dispatch(s.blur, {&s.params, &s.planes[1], &s.planes[2]}, {1u}, g, 3 * io::kSsimGrads);
  }
  batch.dispatch(s.finish,
                 {&s.params, buffers.rgb, buffers.target_rgb, ignore, &s.planes[2], buffers.d_rgb,
                  &s.partials},
                 {}, g);
  batch.dispatch(s.sum, {&s.partials, &s.sums}, {g, io::kLossPartials}, 1);
  batch.download(s.sums, s.host_sums, sizeof(s.host_sums));
}

MappingLossKernels::Result MappingLossKernels::result() const {
  const Impl& s = *impl_;
  const double* sums = s.host_sums;
  Result r;
  // weight x (1 - mean SSIM) = weight / (3 W H) x sum of (1 - SSIM).
  r.loss = s.color_scale * sums[io::kLossColorL1] + s.depth_scale * sums[io::kLossDepthL1] +
           (s.ssim_on ? s.ssim_scale * sums[io::kLossDssim] : 0.0);
  r.d_vignetting = {sums[io::kLossVignetteK1], sums[io::kLossVignetteK2]};
  return r;
}

}  // namespace splat::vk
