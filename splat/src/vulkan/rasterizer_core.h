// What the resident map (resident_map.cpp) needs of the Vulkan rasterizer: its device, its
// command batch, and its forward and backward stages recorded on a map that stays on the device.
#pragma once
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "shader_io.h"
#include "splat/rasterizer.h"
#include "splat/resident_map.h"
#include "vulkan/compute.h"
#include "vulkan/device_sort.h"

namespace splat::vk {

// Workgroups of kGroupSize invocations that cover `count` items.
inline uint32_t groups_for(std::size_t count) {
  return static_cast<uint32_t>((count + io::kGroupSize - 1) / io::kGroupSize);
}

// A map's five parameter arrays on the device (frame.glsl's bindings 1..5).
struct DeviceMap {
  const Buffer* means = nullptr;
  const Buffer* log_scales = nullptr;
  const Buffer* rotations = nullptr;
  const Buffer* opacity_logits = nullptr;
  const Buffer* sh = nullptr;
  uint32_t count = 0;
  int sh_degree = 0;
};

class RasterizerCore {
 public:
  virtual ~RasterizerCore() = default;
  virtual Context& context() = 0;
  // The batch every stage records into; use it only while holding lock().
  virtual CommandBatch& batch() = 0;
  virtual std::unique_lock<std::mutex> lock() = 0;
  virtual PrefixSum& prefix_sum() = 0;

  // Which images a render brings back to the host.
  enum class Download {
    kNone,      // none: the last submission stays recorded for the caller to extend and run
    kCoverage,  // alpha and depth_normalized
    kImages,    // every image
  };
  // Renders the device map (caller holds lock()) into `images` as `download` says (images may be
  // null with kNone). Returns the frame's device state, for images() and record_backward().
  virtual std::shared_ptr<void> render(const DeviceMap& map, const Camera& camera, const RenderSettings& settings,
                                       ForwardResult* images, Download download) = 0;
  struct Images {
    const Buffer* rgb = nullptr;    // [H, W, 3]
    const Buffer* alpha = nullptr;  // [H, W]
    const Buffer* depth = nullptr;  // [H, W], alpha-weighted
    const Buffer* depth_normalized = nullptr;  // [H, W], depth / alpha where alpha > 0
  };
  virtual Images images(const std::shared_ptr<void>& frame) = 0;
  // Records the backward pass from image gradients on the device and the download of the sums
  // of its pose partials (dL/dW row-major, dL/dt: kPosePartials values) into `pose_sums`, which
  // must stay valid until the batch runs. Returns the gradients: [N, kGeometryFloats], [N, K, 3].
  struct Gradients {
    const Buffer* geometry = nullptr;
    const Buffer* sh = nullptr;
  };
  virtual Gradients record_backward(const std::shared_ptr<void>& frame, const Buffer& d_rgb,
                                    const Buffer& d_alpha, const Buffer& d_depth,
                                    double* pose_sums) = 0;
  // dL/d(pose) of the frame's camera from its pose sums.
  virtual PoseGradient pose_gradient(const double* pose_sums, const Camera& camera) const = 0;
};

// The resident map of a Vulkan rasterizer, which must outlive it.
std::unique_ptr<ResidentMap> make_resident_map(RasterizerCore& core, int sh_degree);

}  // namespace splat::vk
