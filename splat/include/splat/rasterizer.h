#pragma once
#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "splat/camera.h"
#include "splat/gaussians.h"

namespace splat {

class ThreadPool;

class ResidentMap;

struct RenderSettings {
  std::array<float, 3> background{0.f, 0.f, 0.f};  // RGB behind the splats
  // Highest SH degree evaluated; -1 uses the map's. Lower values ignore the extra coefficients.
  int sh_degree = -1;
  // Backward: propagate the gradient through the SH view direction (mean - camera centre) to
  // the means and the pose. This is the exact derivative. false treats the direction as a
  // constant, as gsplat's rasterization() does (its golden gradients are made that way).
  bool sh_direction_gradient = true;
  // Fill ForwardResult's per-Gaussian and per-tile buffers (means2d .. final_transmittance).
  // false lets a backend leave them empty: the Vulkan backend then skips copying them to the
  // host, which at 1M Gaussians costs more than rendering. Backward works either way.
  bool intermediates = true;
};

// Settings for loops that only use the images (tracking, mapping): no intermediates.
inline RenderSettings images_only() {
  RenderSettings s;
  s.intermediates = false;
  return s;
}

// Counts of what the projection stage did, for logs and tests.
struct RenderStats {
  std::size_t visible = 0;            // splats that reached at least one tile
  std::size_t culled_depth = 0;       // behind the near plane or past the far plane
  std::size_t culled_degenerate = 0;  // zero quaternion or singular 2D covariance
  std::size_t culled_faint = 0;       // opacity below kAlphaMin
  std::size_t culled_offscreen = 0;   // extent box entirely outside the image
  std::size_t intersections = 0;      // (splat, tile) pairs composited
};

// Everything the forward pass produced. Images are [H, W, C] row-major. The intermediate
// buffers are exposed so a mismatch between backends can be traced to one stage.
template <typename Scalar>
struct ForwardResultT {
  int width = 0, height = 0;
  std::vector<Scalar> rgb;    // [H, W, 3] composited over RenderSettings::background
  std::vector<Scalar> alpha;  // [H, W] silhouette, 1 - final transmittance
  std::vector<Scalar> depth;  // [H, W] sum of blend weight x camera z (expected depth x alpha)
  std::vector<Scalar> depth_normalized;  // [H, W] depth / alpha where alpha > 0, else 0; metres

  // Per Gaussian, [N, ...]; radii == 0 on both axes means culled.
  std::vector<Scalar> means2d;   // [N, 2] pixels
  std::vector<Scalar> conics;    // [N, 3] inverse 2D covariance (a, b, c) = [[a, b], [b, c]]
  std::vector<Scalar> depths;    // [N] camera z
  std::vector<int32_t> radii;    // [N, 2] screen extent in pixels along x and y
  std::vector<Scalar> colors;    // [N, 3] SH colour for this view, max(SH + 0.5, 0)
  std::vector<Scalar> opacities; // [N] sigmoid(logit)

  // Tiles: ranges into sorted_ids, [T, 2] begin/end, tiles row-major (tile_y * tiles_x + tile_x).
  int tiles_x = 0, tiles_y = 0;
  std::vector<uint32_t> tile_ranges;
  std::vector<uint32_t> sorted_ids;  // Gaussian index of each intersection, by (tile, depth)
  // Per pixel: one past the last sorted position that contributed, and the final transmittance.
  std::vector<uint32_t> last_contributor;    // [H, W]
  std::vector<Scalar> final_transmittance;   // [H, W]

  RenderStats stats;

  // Inputs, kept for the backward pass. The Gaussians viewed must outlive this result.
  GaussiansViewT<Scalar> gaussians;
  Camera camera;
  RenderSettings settings;

  // Opaque state of the backend that rendered it (the Vulkan backend keeps the frame's device
  // buffers here so backward and pose_jacobian need no re-upload); null for the CPU backend.
  std::shared_ptr<void> backend_state;
};
using ForwardResult = ForwardResultT<float>;

// Upstream gradients dL/d(output image). An empty vector means zero for that output.
template <typename Scalar>
struct ImageGradsT {
  std::vector<Scalar> rgb;    // [H, W, 3]
  std::vector<Scalar> alpha;  // [H, W]
  std::vector<Scalar> depth;  // [H, W], with respect to ForwardResult::depth (not normalized)
};
using ImageGrads = ImageGradsT<float>;

// Pose gradient for the left perturbation T_cam_world <- exp(delta) * T_cam_world,
// delta = [v, omega] (translation first), as in ../STYLE.md.
using PoseGradient = Eigen::Matrix<double, 6, 1>;

template <typename Scalar>
struct BackwardResultT {
  GaussianGradsT<Scalar> d_gaussians;  // mirrors the input map, field for field
  PoseGradient d_loss_d_pose = PoseGradient::Zero();
};
using BackwardResult = BackwardResultT<float>;

// The differentiable tile rasterizer. Backends differ in where they run, never in the maths.
class Rasterizer {
 public:
  virtual ~Rasterizer() = default;
  virtual std::string name() const = 0;
  // Renders the map. Throws splat::Error for invalid sizes, non-finite values or a bad camera.
  virtual ForwardResult forward(const GaussiansView& gaussians, const Camera& camera,
                                const RenderSettings& settings) = 0;
  // Gradients of a loss given its gradients with respect to the forward outputs.
  // Throws splat::Error if the image gradients do not match the forward result's size.
  virtual BackwardResult backward(const ForwardResult& forward, const ImageGrads& d_image) = 0;
  // Per-pixel Jacobian of (r, g, b, depth, alpha) with respect to the camera pose (the left
  // perturbation above), [H, W, 5, 6]: what Gauss-Newton pose tracking needs. `jacobian` is
  // resized and overwritten; passing the same vector call after call reuses its memory (at
  // 640x480 it is 37 MB, which would otherwise be mapped and zeroed on every call).
  virtual void pose_jacobian(const ForwardResult& forward, std::vector<float>& jacobian) = 0;
  // Device memory the backend holds now, in bytes (0 for the CPU backend).
  virtual std::size_t device_memory_bytes() const { return 0; }
  // Bytes moved between host and device memory since the last reset, each way (none for the CPU
  // backend): what a render or a mapping iteration costs on the bus.
  struct Transfers {
    std::size_t to_device = 0, to_host = 0;
  };
  virtual Transfers transfers() const { return {}; }
  virtual void reset_transfers() {}
  // Time per stage since the last reset, in milliseconds, where the backend can measure it:
  // device time per shader (Vulkan timestamps) or wall time per pipeline stage (CPU). For
  // profiling.
  virtual std::map<std::string, double> stage_times_ms() const { return {}; }
  virtual void reset_stage_times() {}
  // A map kept by this backend between calls, with its Adam state (resident_map.h), so mapping
  // steps move no map over a bus; it must not outlive the rasterizer. Null where the backend
  // works on the host's map anyway (CPU): callers then use forward() and backward().
  virtual std::unique_ptr<ResidentMap> make_resident_map(int sh_degree);
  // The backend's own worker threads, which the host work between its calls (losses, Adam) may
  // share while no render runs; null where the backend keeps none (Vulkan).
  virtual ThreadPool* host_threads() { return nullptr; }
};

// Throws splat::Error unless every non-empty image gradient has the forward result's size.
template <typename Scalar>
void validate_image_grads(const ForwardResultT<Scalar>& forward, const ImageGradsT<Scalar>& d_image);

// dL/d(pose) for the left perturbation from dL/dW and dL/dt of p_cam = W p_world + t, where
// W, t are T_cam_world as the backend used it (in its precision). Shared by both backends.
PoseGradient pose_gradient_from(const Eigen::Matrix3d& d_w, const Eigen::Vector3d& d_t,
                                const Eigen::Matrix3d& w, const Eigen::Vector3d& t);

struct CpuOptions {
  int threads = 0;  // 0 = all hardware threads
};
std::unique_ptr<Rasterizer> make_cpu_rasterizer(const CpuOptions& options = {});

}  // namespace splat
