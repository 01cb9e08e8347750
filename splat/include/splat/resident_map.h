// A map kept where a backend computes (device memory for Vulkan), with its Adam state and the
// frames it is fitted to, optimized one mapping step at a time: during optimization neither the
// map nor its gradients cross the bus, only a few scalars per step (the loss, the pose and
// vignetting gradients). Whole-map transfers happen when the host asks for the map.
#pragma once
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "splat/adam.h"
#include "splat/camera.h"
#include "splat/gaussians.h"
#include "splat/rasterizer.h"
#include "splat/rgbd_frame.h"

namespace splat {

// Verdicts of the free-space test of a Gaussian's centre against a frame's depth
// (ResidentMap::free_space_test).
enum class FreeSpace : uint8_t {
  kNone = 0,     // no verdict: off the image, too near, or a pixel around it unmeasured
  kThrough = 1,  // every depth around it is farther than the centre by more than the margin
  kOn = 2,       // a depth around it is within the margin of the centre
};

// The mapping loss, as the CPU composes it from losses.h: color_weight x l1_loss plus
// ssim_weight x dssim_loss of the colour the camera records (the render times the vignetting
// gain 1 + k1 r^2 + k2 r^4, r^2 = ((x + 0.5 - cx) / fx)^2 + ((y + 0.5 - cy) / fy)^2), plus
// depth_weight x silhouette_depth_l1_loss. Ignored pixels of the target take the recorded
// render as their colour and have no depth measurement: they pull nowhere.
struct MappingLoss {
  double color_weight = 0.5, ssim_weight = 0.1, depth_weight = 1.0;
  double depth_alpha_threshold = 0.95;
  double vignetting_k1 = 0, vignetting_k2 = 0;
};

// Adam's learning rates per parameter group (times lr_scale in a step) and its constants.
struct AdamRates {
  double means = 0, log_scales = 0, rotations = 0, opacity_logits = 0;
  double sh_dc = 0, sh_rest = 0;  // SH coefficient 0, and the higher degrees
  AdamHyper hyper;
};

// Adam's state per Gaussian, aligned with the map: the moments field for field, and the step
// count of each Gaussian (Gaussians added later get their own bias correction).
struct AdamMoments {
  Gaussians m, v;
  std::vector<uint32_t> steps;
};

struct MappingStepResult {
  double loss = 0;
  PoseGradient d_loss_d_pose = PoseGradient::Zero();
  std::array<double, 2> d_loss_d_vignetting = {0, 0};  // k1, k2
};

class ResidentMap {
 public:
  virtual ~ResidentMap() = default;
  virtual std::size_t size() const = 0;
  virtual int sh_degree() const = 0;

  // Replaces the map and its Adam state; null moments start from zero.
  virtual void assign(const Gaussians& map, const AdamMoments* moments) = 0;
  // Appends Gaussians (of the map's SH degree) with zero moments and step counts.
  virtual void append(const GaussiansView& added) = 0;
  // Keeps the Gaussians where keep[i] != 0, in order.
  virtual void keep(std::span<const uint8_t> keep) = 0;
  // The map, and its Adam state where `moments` is given: a whole-map transfer.
  virtual void read(Gaussians& map, AdamMoments* moments) = 0;
  // One parameter group, [N, width].
  virtual std::vector<float> read_group(ParamGroup group) = 0;

  // Tests run where the map is, so that only their verdicts cross the bus (bits per Gaussian).
  // The free-space test of each Gaussian's centre from `first` on against the depth of the frame
  // stored under `key`, seen from `camera` (its size): the verdict of its pixel's 3x3
  // neighbourhood, with no verdict for a centre nearer than near_z or within a pixel of the
  // border, and a margin of margin + margin_per_metre x the centre's depth.
  struct FreeSpaceTest {
    float near_z = 0, margin = 0, margin_per_metre = 0;  // the caller's (mapping's) values
  };
  virtual std::vector<FreeSpace> free_space_test(uint64_t key, const Camera& camera, std::size_t first,
                                                 const FreeSpaceTest& test) = 0;
  // Densification's coverage test of the map seen from `camera` against the frame stored under
  // `key` (its size): per pixel 1 where the map should be seeded there, that is where the
  // render's alpha is below densify_alpha, or where the measured depth lies in front of the
  // rendered depth (depth_normalized) by more than depth_error_factor x the median of
  // |rendered - measured| over the measured pixels the render covers (alpha above
  // densify_alpha), that median taken as at least min_median; 0 on ignored pixels. In float.
  // Only the mask crosses the bus, a bit a pixel. Throws splat::Error for an empty map.
  struct CoverageTest {
    float densify_alpha = 0, depth_error_factor = 0, min_median = 0;  // the caller's (mapping's) values
  };
  virtual std::vector<uint8_t> coverage_mask(uint64_t key, const Camera& camera, const CoverageTest& test) = 0;
  // Per Gaussian, 1 where its opacity logit is below min_opacity_logit or its largest log scale
  // above max_log_scale: pruning's test.
  virtual std::vector<uint8_t> faint_or_oversized(float min_opacity_logit, float max_log_scale) = 0;

  // Stores a frame to fit under `key` (its colour, depth and ignore mask), replacing any frame
  // stored under it; the frame's camera gives the image size. Frames stay until dropped.
  virtual void set_target(uint64_t key, const RgbdFrame& frame) = 0;
  virtual void drop_target(uint64_t key) = 0;
  virtual bool has_target(uint64_t key) const = 0;

  // Renders the map: its images (ForwardResult's intermediates stay empty), or where
  // `coverage_only` just alpha and depth_normalized (what densification tests): a third of the
  // bytes.
  virtual ForwardResult render(const Camera& camera, const RenderSettings& settings, bool coverage_only) = 0;
  // One step: render at `camera` (the target's size), the loss against target `key`, its
  // gradients, and Adam on every Gaussian at rates x lr_scale. `isotropic` moves the three log
  // scales of a Gaussian together and leaves rotations. Throws splat::Error for an unknown key,
  // a camera of another size or an empty map.
  virtual MappingStepResult step(uint64_t key, const Camera& camera, const MappingLoss& loss,
                                 const AdamRates& rates, double lr_scale, bool isotropic) = 0;
};

}  // namespace splat
