// The mapping loss (splat::MappingLoss) and its gradients as compute shaders, so a mapping step
// needs no image on the host: pointwise terms (L1 colour, silhouette depth, vignetting, ignored
// pixels) and the local statistics of D-SSIM, their separable blurs, the SSIM terms and their
// adjoint blurs, then the gradient through the vignetting. Per-workgroup partial sums come back
// and are added in double on the host, as the CPU losses add theirs.
#pragma once
#include <array>
#include <cstddef>
#include <memory>
#include <vector>

#include "splat/camera.h"
#include "splat/resident_map.h"
#include "vulkan/compute.h"

namespace splat::vk {

// Device buffers of one evaluation; float unless said, [H, W] or [H, W, 3] row-major.
struct LossBuffers {
  const Buffer* rgb = nullptr;           // the render (radiance, before vignetting), [H, W, 3]
  const Buffer* alpha = nullptr;         // the render's silhouette
  const Buffer* depth = nullptr;         // ForwardResult::depth (alpha-weighted)
  const Buffer* target_rgb = nullptr;    // [H, W, 3]
  const Buffer* target_depth = nullptr;  // 0 = no measurement
  const Buffer* ignore = nullptr;        // uint32, non-zero = ignored; null: none ignored
  Buffer* d_rgb = nullptr;               // dL/d(rgb), overwritten
  Buffer* d_alpha = nullptr;             // dL/d(alpha), overwritten
  Buffer* d_depth = nullptr;             // dL/d(depth), overwritten
};

class MappingLossKernels {
 public:
  explicit MappingLossKernels(Context& context);

  // Records the loss at the camera's size and intrinsics into `batch`. `measured` is the
  // number of pixels whose target depth is > 0 and that are not ignored (the depth term's
  // mean is over them). result() is valid after batch.run().
  void record(CommandBatch& batch, const LossBuffers& buffers, const Camera& camera,
              const MappingLoss& loss, std::size_t measured);

  struct Result {
    double loss = 0;
    std::array<double, 2> d_vignetting = {0, 0};  // dL/d(k1, k2)
  };
  Result result() const;

 private:
  struct Impl;
  std::shared_ptr<Impl> impl_;
};

}  // namespace splat::vk
