// The Vulkan backend: the CPU reference's stages as compute shaders (shaders/*.comp).
// forward: project -> radix sort by depth -> count, scan and emit (tile, instance) pairs ->
// stable radix sort by tile -> tile ranges -> composite. Two submissions, because the number of
// intersections must be known before their buffers are sized. backward and pose_jacobian
// reuse the forward pass's device buffers, held by the ForwardResult.
#include "splat/vulkan_rasterizer.h"

#include <bit>
#include <memory>
#include <mutex>
#include <vector>

#include "heap_tuning.h"
#include "project_backward_spv.h"
#include "project_forward_spv.h"
#include "partials_sum_float_spv.h"
#include "project_pose_jvp_spv.h"
#include "rasterize_backward_atomic_spv.h"
#include "rasterize_backward_spv.h"
#include "rasterize_forward_spv.h"
#include "rasterize_pose_jvp_spv.h"
#include "render_stats.h"
#include "shader_io.h"
#include "splat/error.h"
#include "tiles_count_spv.h"
#include "tiles_emit_spv.h"
#include "tiles_finish_spv.h"
#include "vulkan/device_sort.h"
#include "vulkan/rasterizer_core.h"

namespace splat::vk {
namespace {

constexpr uint32_t kParamFloats = io::kGeometryFloats;  // d_params per Gaussian

// Device buffers of one rendered frame; recycled through the rasterizer's pool.
struct FrameState {
  explicit FrameState(Context& c)
      : frame(c),
        means(c),
        log_scales(c),
        rotations(c),
        opacity_logits(c),
        sh(c),
        means2d(c),
        conics(c),
        depths(c),
        radii(c),
        colors(c),
        opacities(c),
        tile_counts(c),
        depth_keys(c),
        depth_order(c),
        depth_keys_tmp(c),
        depth_order_tmp(c),
        cull(c),
        offsets(c),
        total(c),
        tile_keys(c),
        instances(c),
        tile_keys_tmp(c),
        instances_tmp(c),
        instance_gaussian(c),
        first_instance(c),
        sorted_ids(c),
        sorted_position(c),
        tile_ranges(c),
        rgb(c),
        alpha(c),
        depth(c),
        depth_normalized(c),
        last(c),
        transmittance(c) {}

  const void* owner = nullptr;
  DeviceMap map;  // the map this frame rendered: its own uploaded copy or a resident map
  Buffer frame, means, log_scales, rotations, opacity_logits, sh;
  Buffer means2d, conics, depths, radii, colors, opacities, tile_counts;
  Buffer depth_keys, depth_order, depth_keys_tmp, depth_order_tmp, cull, offsets, total;
  Buffer tile_keys, instances, tile_keys_tmp, instances_tmp, instance_gaussian, first_instance;
  Buffer sorted_ids, sorted_position, tile_ranges;
  Buffer rgb, alpha, depth, depth_normalized, last, transmittance;
  // Where the sorts left their results (ping-pong), and the frame's sizes.
  Buffer* order = nullptr;
  uint32_t count = 0, intersections = 0, tiles_x = 0, tiles_y = 0;
};

// Pool of frame states. A ForwardResult may outlive the rasterizer, so states share ownership
// of the context and return to the pool only while it exists.
struct StatePool {
  std::mutex mutex;
  std::vector<std::unique_ptr<FrameState>> free;
};

io::FrameParams make_params(const Camera& camera, const RenderSettings& settings, int map_degree,
                            std::size_t count) {
  io::FrameParams p{};
  // As the CPU reference's CameraModel: everything in float.
  p.fx = float(camera.fx);
  p.fy = float(camera.fy);
  p.cx = float(camera.cx);
  p.cy = float(camera.cy);
  p.near_z = float(camera.near);
  p.far_z = float(camera.far);
  const Eigen::Matrix3f w = camera.T_cam_world.linear().cast<float>();
  const Eigen::Vector3f t = camera.T_cam_world.translation().cast<float>();
  const Eigen::Vector3f position = -(w.transpose() * t);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) p.rotation[r * 3 + c] = w(r, c);
    p.translation[r] = t[r];
    p.cam_position[r] = position[r];
    p.background[r] = settings.background[r];
  }
  const float width = float(camera.width), height = float(camera.height);
  const float tan_fovx = 0.5f * width / p.fx, tan_fovy = 0.5f * height / p.fy;
  p.lim_x_pos = (width - p.cx) / p.fx + io::kFovClampMargin * tan_fovx;
  p.lim_x_neg = p.cx / p.fx + io::kFovClampMargin * tan_fovx;
  p.lim_y_pos = (height - p.cy) / p.fy + io::kFovClampMargin * tan_fovy;
  p.lim_y_neg = p.cy / p.fy + io::kFovClampMargin * tan_fovy;
  p.width = uint32_t(camera.width);
  p.height = uint32_t(camera.height);
  p.tiles_x = (p.width + io::kTileSize - 1) / io::kTileSize;
  p.tiles_y = (p.height + io::kTileSize - 1) / io::kTileSize;
  p.count = uint32_t(count);
  p.sh_degree = settings.sh_degree < 0 ? map_degree : std::min(map_degree, settings.sh_degree);
  p.sh_stride = uint32_t(sh_coeff_count(map_degree));
  p.sh_direction_gradient = settings.sh_direction_gradient ? 1u : 0u;
  return p;
}

template <typename T>
void reserve_upload(CommandBatch& batch, Buffer& buffer, std::span<const T> data) {
  buffer.reserve(data.size_bytes());
  batch.upload(buffer, data.data(), data.size_bytes());
}

template <typename T>
void download_into(CommandBatch& batch, const Buffer& buffer, std::vector<T>& out,
                   std::size_t count) {
  out.resize(count);
  batch.download(buffer, out.data(), count * sizeof(T));
}

class VulkanRasterizer final : public Rasterizer, public RasterizerCore {
 public:
  explicit VulkanRasterizer(const VulkanOptions& options)
      : context_(std::make_shared<Context>(options)),
        pool_(std::make_shared<StatePool>()),
        batch_(*context_),
        scan_(*context_),
        sort_(*context_, scan_),
        project_forward_(*context_, kProjectForwardSpv, 16, "project_forward"),
        tiles_count_(*context_, kTilesCountSpv, 3, "tiles_count"),
        tiles_emit_(*context_, kTilesEmitSpv, 9, "tiles_emit"),
        tiles_finish_(*context_, kTilesFinishSpv, 6, "tiles_finish"),
        rasterize_forward_(*context_, kRasterizeForwardSpv, 14, "rasterize_forward"),
        rasterize_backward_(*context_,
                            context_->float_atomics_enabled()
                                ? std::span<const uint32_t>(kRasterizeBackwardAtomicSpv)
                                : std::span<const uint32_t>(kRasterizeBackwardSpv),
                            14, "rasterize_backward"),
        project_backward_(*context_, kProjectBackwardSpv, 16, "project_backward"),
        project_pose_jvp_(*context_, kProjectPoseJvpSpv, 9, "project_pose_jvp"),
        rasterize_pose_jvp_(*context_, kRasterizePoseJvpSpv, 11, "rasterize_pose_jvp"),
        partials_sum_(*context_, kPartialsSumFloatSpv, 2, "partials_sum"),
        d_rgb_(*context_),
        d_alpha_(*context_),
        d_depth_(*context_),
        isect_grads_(*context_),
        d_params_(*context_),
        d_sh_(*context_),
        pose_partials_(*context_),
        pose_sums_(*context_),
        screen_jvp_(*context_),
        jacobian_(*context_) {}

  std::string name() const override {
    const VulkanDeviceInfo& info = context_->info();
    return "vulkan (device " + std::to_string(info.index) + ": " + info.name + ", " + info.type +
           (context_->float_atomics_enabled() ? ", float atomics" : ", portable reduction") + ")";
  }

  std::size_t device_memory_bytes() const override { return context_->allocated_bytes(); }
  std::map<std::string, double> stage_times_ms() const override { return batch_.kernel_ms(); }
  void reset_stage_times() override { batch_.reset_kernel_ms(); }
  Transfers transfers() const override { return {batch_.uploaded_bytes(), batch_.downloaded_bytes()}; }
  void reset_transfers() override { batch_.reset_transfer_counts(); }
  std::unique_ptr<ResidentMap> make_resident_map(int sh_degree) override {
    return vk::make_resident_map(*this, sh_degree);
  }

  // RasterizerCore
  Context& context() override { return *context_; }
  CommandBatch& batch() override { return batch_; }
  std::unique_lock<std::mutex> lock() override { return std::unique_lock(mutex_); }
  PrefixSum& prefix_sum() override { return scan_; }
  std::shared_ptr<void> render(const DeviceMap& map, const Camera& camera,
                               const RenderSettings& settings, ForwardResult* images, Download download) override {
    camera.validate("rasterize");
    std::shared_ptr<FrameState> state = acquire_state();
    ForwardResult local;
    ForwardResult& f = images ? *images : local;
    f.camera = camera;
    f.settings = settings;
    f.settings.intermediates = false;
    f.gaussians.sh_degree = map.sh_degree;
    render(*state, f, &map, download);
    return state;
  }
  Images images(const std::shared_ptr<void>& frame) override {
    const FrameState& s = *std::static_pointer_cast<FrameState>(frame);
    return {&s.rgb, &s.alpha, &s.depth, &s.depth_normalized};
  }
  Gradients record_backward(const std::shared_ptr<void>& frame, const Buffer& d_rgb,
                            const Buffer& d_alpha, const Buffer& d_depth,
                            double* pose_sums) override {
    FrameState& s = *std::static_pointer_cast<FrameState>(frame);
    pose_sums_.reserve(io::kPosePartials * sizeof(double));
    record_backward(s, d_rgb, d_alpha, d_depth, {1u, 1u, 1u});
    batch_.dispatch(partials_sum_, {&pose_partials_, &pose_sums_}, {groups_for(s.count), io::kPosePartials}, 1);
    batch_.download(pose_sums_, pose_sums, io::kPosePartials * sizeof(double));
    return {&d_params_, &d_sh_};
  }
  PoseGradient pose_gradient(const double* sums, const Camera& camera) const override {
    Eigen::Matrix3d d_w;
    for (int k = 0; k < 9; ++k) d_w(k / 3, k % 3) = sums[k];
    const Eigen::Vector3d d_t(sums[9], sums[10], sums[11]);
    return pose_gradient_from(d_w, d_t, camera.T_cam_world.linear().cast<float>().cast<double>(),
                              camera.T_cam_world.translation().cast<float>().cast<double>());
  }

  ForwardResult forward(const GaussiansView& gaussians, const Camera& camera,
                        const RenderSettings& settings) override {
    validate(gaussians, "rasterize");
    camera.validate("rasterize");
    std::lock_guard lock(mutex_);
    std::shared_ptr<FrameState> state = acquire_state();
    ForwardResult f;
    f.gaussians = gaussians;
    f.camera = camera;
    f.settings = settings;
    render(*state, f, nullptr, Download::kImages);
    f.backend_state = state;
    return f;
  }

  BackwardResult backward(const ForwardResult& forward, const ImageGrads& d_image) override {
    validate_image_grads(forward, d_image);
    std::lock_guard lock(mutex_);
    std::shared_ptr<FrameState> state = state_of(forward);
    FrameState& s = *state;
    const std::size_t n = s.count, pixels = std::size_t(forward.width) * forward.height;
    d_rgb_.reserve(pixels * 3 * 4);
    d_alpha_.reserve(pixels * 4);
    d_depth_.reserve(pixels * 4);
    batch_.upload(d_rgb_, d_image.rgb.data(), d_image.rgb.size() * 4);
    batch_.upload(d_alpha_, d_image.alpha.data(), d_image.alpha.size() * 4);
    batch_.upload(d_depth_, d_image.depth.data(), d_image.depth.size() * 4);
    record_backward(s, d_rgb_, d_alpha_, d_depth_,
                    {uint32_t(!d_image.rgb.empty()), uint32_t(!d_image.alpha.empty()),
                     uint32_t(!d_image.depth.empty())});
    std::vector<float> params, partials;
    BackwardResult out;
    GaussianGrads& d = out.d_gaussians;
    d.sh_degree = forward.gaussians.sh_degree;
    d.resize(n);
    download_into(batch_, d_params_, params, n * kParamFloats);
    download_into(batch_, pose_partials_, partials, std::size_t(groups_for(n)) * io::kPosePartials);
    batch_.download(d_sh_, d.sh.data(), d.sh.size() * 4);
    batch_.run();

    for (std::size_t i = 0; i < n; ++i) {
      const float* p = &params[i * kParamFloats];
      for (int k = 0; k < 3; ++k) {
        d.means[i * 3 + k] = p[k];
        d.log_scales[i * 3 + k] = p[3 + k];
      }
      for (int k = 0; k < 4; ++k) d.rotations[i * 4 + k] = p[6 + k];
      d.opacity_logits[i] = p[10];
    }
    double sums[io::kPosePartials] = {};
    for (std::size_t g = 0; g < partials.size() / io::kPosePartials; ++g) {
      for (std::size_t k = 0; k < io::kPosePartials; ++k) sums[k] += partials[g * io::kPosePartials + k];
    }
    out.d_loss_d_pose = pose_gradient(sums, forward.camera);
    return out;
  }

  void pose_jacobian(const ForwardResult& forward, std::vector<float>& out) override {
    std::lock_guard lock(mutex_);
    std::shared_ptr<FrameState> state = state_of(forward);
    FrameState& s = *state;
    const std::size_t pixels = std::size_t(forward.width) * forward.height;
    const std::size_t values = pixels * io::kPoseJacobianOutputs * 6;
    screen_jvp_.reserve(std::size_t(s.count) * io::kScreenValues * 6 * 4);
    jacobian_.reserve(values * 4);
    batch_.dispatch(project_pose_jvp_,
                    {&s.frame, s.map.means, s.map.log_scales, s.map.rotations,
                     s.map.opacity_logits, s.map.sh, &s.conics, &s.radii, &screen_jvp_},
                    {}, groups_for(s.count));
    batch_.dispatch(rasterize_pose_jvp_,
                    {&s.frame, &s.tile_ranges, &s.sorted_ids, &s.means2d, &s.conics, &s.opacities,
                     &s.colors, &s.depths, &s.last, &screen_jvp_, &jacobian_},
                    {}, s.tiles_x, s.tiles_y);
    download_into(batch_, jacobian_, out, values);
    batch_.run();
  }

 private:
  std::shared_ptr<FrameState> acquire_state() {
    std::unique_ptr<FrameState> state;
    {
      std::lock_guard lock(pool_->mutex);
      if (!pool_->free.empty()) {
        state = std::move(pool_->free.back());
        pool_->free.pop_back();
      }
    }
    if (!state) state = std::make_unique<FrameState>(*context_);
    state->owner = this;
    std::weak_ptr<StatePool> pool = pool_;
    std::shared_ptr<Context> keep_alive = context_;
    return std::shared_ptr<FrameState>(state.release(), [pool, keep_alive](FrameState* s) {
      std::unique_ptr<FrameState> owned(s);
      if (auto p = pool.lock()) {
        std::lock_guard lock(p->mutex);
        p->free.push_back(std::move(owned));
      }
      // else: destroyed here, while keep_alive still holds the context
    });
  }

  // The device state of a forward result from this rasterizer, or a fresh render of its inputs.
  std::shared_ptr<FrameState> state_of(const ForwardResult& forward) {
    auto state = std::static_pointer_cast<FrameState>(forward.backend_state);
    if (state && state->owner == this) return state;
    state = acquire_state();
    ForwardResult again;
    again.gaussians = forward.gaussians;
    again.camera = forward.camera;
    again.settings = forward.settings;
    render(*state, again, nullptr, Download::kImages);
    return state;
  }

  // Records rasterize and project backward of a rendered frame from image gradients already on
  // the device; `used` says which of d_rgb, d_alpha, d_depth hold gradients (the others are 0).
  void record_backward(FrameState& s, const Buffer& d_rgb, const Buffer& d_alpha,
                       const Buffer& d_depth, std::initializer_list<uint32_t> used) {
    const std::size_t n = s.count;
    const int stride_k = sh_coeff_count(s.map.sh_degree);
    // Reserve everything before recording (see device_sort.h).
    isect_grads_.reserve(std::size_t(s.intersections) * io::kGradSlots * 4);
    d_params_.reserve(n * kParamFloats * 4);
    d_sh_.reserve(n * stride_k * 3 * 4);
    pose_partials_.reserve(std::size_t(groups_for(n)) * io::kPosePartials * 4);
    batch_.fill_zero(isect_grads_, std::size_t(s.intersections) * io::kGradSlots * 4);
    batch_.dispatch(
        rasterize_backward_,
        {&s.frame, &s.tile_ranges, &s.sorted_ids, &s.means2d, &s.conics, &s.opacities, &s.colors,
         &s.depths, &s.last, &s.transmittance, &d_rgb, &d_alpha, &d_depth, &isect_grads_},
        used, s.tiles_x, s.tiles_y);
    batch_.dispatch(
        project_backward_,
        {&s.frame, s.map.means, s.map.log_scales, s.map.rotations, s.map.opacity_logits, s.map.sh,
         &s.conics, &s.opacities, &s.radii, &s.tile_counts, &s.first_instance, &s.sorted_position,
         &isect_grads_, &d_params_, &d_sh_, &pose_partials_},
        {}, groups_for(n));
  }

  // Renders f.gaussians, or the device map `resident` where given (f.gaussians then only gives
  // the SH degree), downloading into f what `download` says and then running the batch (kNone:
  // the second submission stays recorded). A resident render reports no cull statistics: they
  // are one word per Gaussian.
  void render(FrameState& s, ForwardResult& f, const DeviceMap* resident, Download download) {
    const GaussiansView& g = f.gaussians;
    const Camera& camera = f.camera;
    const std::size_t n = resident ? resident->count : g.size();
    const int sh_degree = resident ? resident->sh_degree : g.sh_degree;
    const io::FrameParams params = make_params(camera, f.settings, sh_degree, n);
    s.count = uint32_t(n);
    s.tiles_x = params.tiles_x;
    s.tiles_y = params.tiles_y;
    const std::size_t tiles = std::size_t(s.tiles_x) * s.tiles_y;
    const std::size_t pixels = std::size_t(camera.width) * camera.height;

    // Submission 1: projection, depth sort, intersection counts and their total.
    s.frame.reserve(sizeof(params));
    for (Buffer* b :
         {&s.depths, &s.opacities, &s.tile_counts, &s.depth_keys, &s.depth_order, &s.depth_keys_tmp,
          &s.depth_order_tmp, &s.cull, &s.offsets, &s.first_instance}) {
      b->reserve(n * 4);
    }
    s.means2d.reserve(n * 2 * 4);
    s.radii.reserve(n * 2 * 4);
    s.conics.reserve(n * 3 * 4);
    s.colors.reserve(n * 3 * 4);
    s.total.reserve(4);
    sort_.prepare(uint32_t(n));
    scan_.prepare(uint32_t(n));
    batch_.upload(s.frame, &params, sizeof(params));
    if (resident) {
      s.map = *resident;
    } else {
      reserve_upload(batch_, s.means, g.means);
      reserve_upload(batch_, s.log_scales, g.log_scales);
      reserve_upload(batch_, s.rotations, g.rotations);
      reserve_upload(batch_, s.opacity_logits, g.opacity_logits);
      reserve_upload(batch_, s.sh, g.sh);
      s.map = {&s.means, &s.log_scales, &s.rotations, &s.opacity_logits, &s.sh, uint32_t(n), sh_degree};
    }
    batch_.dispatch(project_forward_,
                    {&s.frame, s.map.means, s.map.log_scales, s.map.rotations, s.map.opacity_logits,
                     s.map.sh, &s.means2d, &s.conics, &s.depths, &s.radii, &s.colors, &s.opacities,
                     &s.tile_counts, &s.depth_keys, &s.depth_order, &s.cull},
                    {}, groups_for(n));
    const bool depth_in_tmp = sort_.record(batch_, s.depth_keys, s.depth_order, s.depth_keys_tmp,
                                           s.depth_order_tmp, uint32_t(n), 32);
    s.order = depth_in_tmp ? &s.depth_order_tmp : &s.depth_order;
    batch_.dispatch(tiles_count_, {s.order, &s.tile_counts, &s.offsets}, {uint32_t(n)},
                    groups_for(n));
    scan_.record(batch_, s.offsets, uint32_t(n), &s.total);
    uint32_t intersections = 0;
    batch_.download(s.total, &intersections, 4);
    batch_.run();
    s.intersections = intersections;

    // Submission 2: emit and sort (tile, instance) pairs, tile ranges, compositing.
    const std::size_t m = intersections;
    for (Buffer* b : {&s.tile_keys, &s.instances, &s.tile_keys_tmp, &s.instances_tmp,
                      &s.instance_gaussian, &s.sorted_ids, &s.sorted_position}) {
      b->reserve(m * 4);
    }
    s.tile_ranges.reserve(tiles * 2 * 4);
    for (Buffer* b : {&s.alpha, &s.depth, &s.depth_normalized, &s.last, &s.transmittance}) {
      b->reserve(pixels * 4);
    }
    s.rgb.reserve(pixels * 3 * 4);
    sort_.prepare(intersections);
    batch_.dispatch(tiles_emit_,
                    {&s.frame, s.order, &s.offsets, &s.means2d, &s.radii, &s.tile_keys,
                     &s.instances, &s.instance_gaussian, &s.first_instance},
                    {}, groups_for(n));
    const uint32_t tile_bits = std::max(1u, uint32_t(std::bit_width(tiles - 1)));
    const bool tiles_in_tmp = sort_.record(batch_, s.tile_keys, s.instances, s.tile_keys_tmp,
                                           s.instances_tmp, intersections, tile_bits);
    Buffer& sorted_keys = tiles_in_tmp ? s.tile_keys_tmp : s.tile_keys;
    Buffer& sorted_instances = tiles_in_tmp ? s.instances_tmp : s.instances;
    batch_.fill_zero(s.tile_ranges, tiles * 2 * 4);
    batch_.dispatch(tiles_finish_,
                    {&sorted_keys, &sorted_instances, &s.instance_gaussian, &s.sorted_ids,
                     &s.sorted_position, &s.tile_ranges},
                    {intersections}, groups_for(m));
    batch_.dispatch(
        rasterize_forward_,
        {&s.frame, &s.tile_ranges, &s.sorted_ids, &s.means2d, &s.conics, &s.opacities, &s.colors,
         &s.depths, &s.rgb, &s.alpha, &s.depth, &s.depth_normalized, &s.last, &s.transmittance},
        {}, s.tiles_x, s.tiles_y);

    f.width = camera.width;
    f.height = camera.height;
    f.tiles_x = int(s.tiles_x);
    f.tiles_y = int(s.tiles_y);
    f.stats.intersections = m;
    if (download == Download::kNone) return;
    if (download == Download::kImages) {
      download_into(batch_, s.rgb, f.rgb, pixels * 3);
      download_into(batch_, s.depth, f.depth, pixels);
    }
    download_into(batch_, s.alpha, f.alpha, pixels);
    download_into(batch_, s.depth_normalized, f.depth_normalized, pixels);
    if (f.settings.intermediates) {
      download_into(batch_, s.last, f.last_contributor, pixels);
      download_into(batch_, s.transmittance, f.final_transmittance, pixels);
      download_into(batch_, s.means2d, f.means2d, n * 2);
      download_into(batch_, s.conics, f.conics, n * 3);
      download_into(batch_, s.depths, f.depths, n);
      download_into(batch_, s.radii, f.radii, n * 2);
      download_into(batch_, s.colors, f.colors, n * 3);
      download_into(batch_, s.opacities, f.opacities, n);
      download_into(batch_, s.tile_ranges, f.tile_ranges, tiles * 2);
      download_into(batch_, s.sorted_ids, f.sorted_ids, m);
    }
    std::vector<uint32_t> cull;
    if (!resident) download_into(batch_, s.cull, cull, n);
    batch_.run();

    if (!resident) f.stats = tally_cull_reasons(cull);
    f.stats.intersections = m;
  }

  std::shared_ptr<Context> context_;
  std::shared_ptr<StatePool> pool_;
  std::mutex mutex_;  // one frame at a time: the batch and the backward buffers are shared
  CommandBatch batch_;
  PrefixSum scan_;
  RadixSort sort_;
  Kernel project_forward_, tiles_count_, tiles_emit_, tiles_finish_, rasterize_forward_,
      rasterize_backward_, project_backward_, project_pose_jvp_, rasterize_pose_jvp_, partials_sum_;
  Buffer d_rgb_, d_alpha_, d_depth_, isect_grads_, d_params_, d_sh_, pose_partials_, pose_sums_,
      screen_jvp_, jacobian_;
};

}  // namespace
}  // namespace splat::vk

namespace splat {

bool vulkan_backend_built() { return true; }

std::vector<VulkanDeviceInfo> list_vulkan_devices() {
  VkInstance instance = vk::create_instance();
  uint32_t count = 0;
  vkEnumeratePhysicalDevices(instance, &count, nullptr);
  std::vector<VkPhysicalDevice> physicals(count);
  vkEnumeratePhysicalDevices(instance, &count, physicals.data());
  std::vector<VulkanDeviceInfo> out;
  for (uint32_t i = 0; i < count; ++i) out.push_back(vk::describe_device(physicals[i], int(i)));
  vkDestroyInstance(instance, nullptr);
  return out;
}

std::unique_ptr<Rasterizer> make_vulkan_rasterizer(const VulkanOptions& options) {
  keep_freed_frame_memory();  // host copies of the images are frame-sized too
  return std::make_unique<vk::VulkanRasterizer>(options);
}

}  // namespace splat
