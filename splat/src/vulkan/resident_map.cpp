// The Vulkan resident map: the map's five arrays, its Adam moments and step counts, and the
// frames it is fitted to live in device buffers. A step records the render, the loss
// (mapping_loss.h), the backward pass and Adam (adam.comp) and runs them in two submissions
// (the render's intersection count comes back in between); pruning compacts on the device
// (compact_flags.comp, the prefix sum, compact.comp) and appends upload only the new rows.
#include <bit>
#include <exception>
#include <map>
#include <string>

#include "adam_spv.h"
#include "compact_flags_spv.h"
#include "compact_spv.h"
#include "coverage_errors_spv.h"
#include "coverage_histogram_spv.h"
#include "coverage_mask_spv.h"
#include "coverage_select_spv.h"
#include "free_space_test_spv.h"
#include "prune_flags_spv.h"
#include "shader_io.h"
#include "splat/error.h"
#include "vulkan/mapping_loss.h"
#include "vulkan/rasterizer_core.h"

namespace splat::vk {
namespace {

static_assert(sizeof(io::AdamParams) == 56 && sizeof(io::FreeSpaceParams) == 96,
              "the parameter blocks must match their std430 layouts");

// Vulkan guarantees 65535 workgroups along x; the loss's stages take 256 pixels each.
constexpr std::size_t kMaxTargetPixels = std::size_t{65535} * io::kGroupSize;

// Discards what the batch recorded when the operation it guards throws half-way: its commands
// refer to buffers the next user of the batch may reallocate.
class DiscardOnThrow {
 public:
  explicit DiscardOnThrow(CommandBatch& batch) : batch_(batch) {}
  ~DiscardOnThrow() {
    if (std::uncaught_exceptions() <= uncaught_) return;
    try {
      batch_.discard();
    } catch (...) {  // already unwinding: the first error is the one to report
    }
  }

 private:
  CommandBatch& batch_;
  int uncaught_ = std::uncaught_exceptions();
};

// The per-Gaussian arrays, each [N, width] 32-bit words.
enum Array { kMeans, kLogScales, kRotations, kOpacity, kSh, kMGeometry, kVGeometry, kMSh, kVSh, kSteps, kArrays };

struct Target {
  explicit Target(Context& c) : rgb(c), depth(c), ignore(c) {}
  Buffer rgb, depth, ignore;
  int width = 0, height = 0;
  bool ignoring = false;
  std::size_t measured = 0;  // pixels with depth that are not ignored
};

class VulkanResidentMap final : public ResidentMap {
 public:
  VulkanResidentMap(RasterizerCore& core, int sh_degree)
      : core_(core),
        context_(core.context()),
        sh_degree_(sh_degree),
        adam_(context_, kAdamSpv, 13, "adam"),
        compact_flags_(context_, kCompactFlagsSpv, 2, "compact_flags"),
        compact_(context_, kCompactSpv, 4, "compact"),
        free_space_(context_, kFreeSpaceTestSpv, 5, "free_space_test"),
        prune_flags_(context_, kPruneFlagsSpv, 3, "prune_flags"),
        coverage_errors_(context_, kCoverageErrorsSpv, 5, "coverage_errors"),
        coverage_histogram_(context_, kCoverageHistogramSpv, 3, "coverage_histogram"),
        coverage_select_(context_, kCoverageSelectSpv, 2, "coverage_select"),
        coverage_mask_(context_, kCoverageMaskSpv, 6, "coverage_mask"),
        loss_(context_),
        adam_params_(context_),
        keep_bits_(context_),
        offsets_(context_),
        test_params_(context_),
        verdicts_(context_),
        coverage_keys_(context_),
        coverage_select_state_(context_),
        coverage_histogram_bins_(context_),
        d_rgb_(context_),
        d_alpha_(context_),
        d_depth_(context_) {
    if (sh_degree < 0 || sh_degree > kMaxShDegree) {
      throw Error("resident map: SH degree " + std::to_string(sh_degree) + " outside 0.." + std::to_string(kMaxShDegree));
    }
    for (int a = 0; a < kArrays; ++a) arrays_.emplace_back(context_);
  }

  std::size_t size() const override { return count_; }
  int sh_degree() const override { return sh_degree_; }

  void assign(const Gaussians& map, const AdamMoments* moments) override {
    validate_sizes(GaussiansView(map), "resident map");
    check_degree(map.sh_degree, "assign");
    if (moments) {
      validate_sizes(GaussiansView(moments->m), "resident map moments");
      validate_sizes(GaussiansView(moments->v), "resident map moments");
      check_degree(moments->m.sh_degree, "assign (first moment)");
      check_degree(moments->v.sh_degree, "assign (second moment)");
      if (moments->m.size() != map.size() || moments->v.size() != map.size() || moments->steps.size() != map.size()) {
        throw Error("resident map: moments for " + std::to_string(moments->m.size()) + " Gaussians, map of " +
                    std::to_string(map.size()));
      }
    }
    auto lock = core_.lock();
    DiscardOnThrow guard(core_.batch());
    count_ = 0;
    write_rows(map, moments, 0);
  }

  void append(const GaussiansView& added) override {
    validate_sizes(added, "resident map append");
    check_degree(added.sh_degree, "append");
    if (added.size() == 0) return;
    auto lock = core_.lock();
    DiscardOnThrow guard(core_.batch());
    Gaussians copy;  // write_rows takes a map; the rows are few next to the map
    copy.sh_degree = added.sh_degree;
    copy.means.assign(added.means.begin(), added.means.end());
    copy.log_scales.assign(added.log_scales.begin(), added.log_scales.end());
    copy.rotations.assign(added.rotations.begin(), added.rotations.end());
    copy.opacity_logits.assign(added.opacity_logits.begin(), added.opacity_logits.end());
    copy.sh.assign(added.sh.begin(), added.sh.end());
    write_rows(copy, nullptr, count_);
  }

  void keep(std::span<const uint8_t> keep) override {
    if (keep.size() != count_) {
      throw Error("resident map: keep has " + std::to_string(keep.size()) + " entries, the map " + std::to_string(count_));
    }
    std::vector<uint32_t> bits((count_ + 31) / 32, 0);
    std::size_t kept = 0;
    for (std::size_t i = 0; i < count_; ++i) {
      if (keep[i]) bits[i / 32] |= 1u << (i % 32), ++kept;
    }
    if (kept == count_) return;
    auto lock = core_.lock();
    CommandBatch& batch = core_.batch();
    DiscardOnThrow guard(batch);
    const uint32_t n = uint32_t(count_);
    keep_bits_.reserve(bits.size() * 4);
    offsets_.reserve(count_ * 4);
    core_.prefix_sum().prepare(n);
    std::vector<Buffer> compacted;
    for (int a = 0; a < kArrays; ++a) {
      compacted.emplace_back(context_);
      // The capacity it had: appends after pruning need not grow and copy it again.
      compacted.back().reserve(std::max(std::max<std::size_t>(kept, 1) * width(a) * 4, arrays_[a].capacity()));
    }
    batch.upload(keep_bits_, bits.data(), bits.size() * 4);
    batch.dispatch(compact_flags_, {&keep_bits_, &offsets_}, {n}, groups_for(n));
    core_.prefix_sum().record(batch, offsets_, n, nullptr);
    for (int a = 0; a < kArrays; ++a) {
      batch.dispatch(compact_, {&keep_bits_, &offsets_, &arrays_[a], &compacted[a]}, {n, uint32_t(width(a))}, groups_for(n));
    }
    batch.run();
    for (int a = 0; a < kArrays; ++a) arrays_[a] = std::move(compacted[a]);
    count_ = kept;
  }

  void read(Gaussians& map, AdamMoments* moments) override {
    auto lock = core_.lock();
    CommandBatch& batch = core_.batch();
    map.sh_degree = sh_degree_;
    map.resize(count_);
    for (ParamGroup group : kAllParamGroups) download(batch, array_of(group), param_group(map, group));
    if (moments) {
      moments->m.sh_degree = moments->v.sh_degree = sh_degree_;
      moments->m.resize(count_);
      moments->v.resize(count_);
      moments->steps.resize(count_);
      std::vector<float> m_geometry, v_geometry;
      download(batch, kMGeometry, m_geometry);
      download(batch, kVGeometry, v_geometry);
      download(batch, kMSh, moments->m.sh);
      download(batch, kVSh, moments->v.sh);
      batch.download(arrays_[kSteps], moments->steps.data(), count_ * 4);
      batch.run();
      split_geometry(m_geometry, moments->m);
      split_geometry(v_geometry, moments->v);
      return;
    }
    batch.run();
  }

  std::vector<float> read_group(ParamGroup group) override {
    auto lock = core_.lock();
    std::vector<float> values;
    download(core_.batch(), array_of(group), values);
    core_.batch().run();
    return values;
  }

  std::vector<FreeSpace> free_space_test(uint64_t key, const Camera& camera, std::size_t first,
                                         const FreeSpaceTest& test) override {
    const Target& t = target(key, camera);
    if (first >= count_) return {};
    auto lock = core_.lock();
    CommandBatch& batch = core_.batch();
    const std::size_t tested = count_ - first, words = (tested + 15) / 16;
    io::FreeSpaceParams p{};
    p.fx = float(camera.fx), p.fy = float(camera.fy), p.cx = float(camera.cx), p.cy = float(camera.cy);
    const Eigen::Matrix3f w = camera.T_cam_world.linear().cast<float>();
    const Eigen::Vector3f tr = camera.T_cam_world.translation().cast<float>();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) p.rotation[r * 3 + c] = w(r, c);
      p.translation[r] = tr[r];
    }
    p.near_z = test.near_z, p.margin = test.margin, p.margin_per_metre = test.margin_per_metre;
    p.width = uint32_t(t.width), p.height = uint32_t(t.height);
    p.first = uint32_t(first), p.count = uint32_t(count_);
    p.has_ignore = t.ignoring ? 1u : 0u;
    test_params_.reserve(sizeof(p));
    verdicts_.reserve(words * 4);
    batch.upload(test_params_, &p, sizeof(p));
    batch.fill_zero(verdicts_, words * 4);
    batch.dispatch(free_space_, {&test_params_, &arrays_[kMeans], &t.depth, t.ignoring ? &t.ignore : &t.depth, &verdicts_},
                   {}, groups_for(tested));
    std::vector<uint32_t> packed(words);
    batch.download(verdicts_, packed.data(), words * 4);
    batch.run();
    static_assert(uint32_t(FreeSpace::kThrough) == io::kFreeSpaceThrough && uint32_t(FreeSpace::kOn) == io::kFreeSpaceOn);
    std::vector<FreeSpace> codes(tested);
    for (std::size_t j = 0; j < tested; ++j) codes[j] = FreeSpace((packed[j / 16] >> (j % 16 * 2)) & 3u);
    return codes;
  }

  std::vector<uint8_t> coverage_mask(uint64_t key, const Camera& camera, const CoverageTest& test) override {
    if (count_ == 0) throw Error("resident map: coverage test of an empty map");
    const Target& t = target(key, camera);
    auto lock = core_.lock();
    CommandBatch& batch = core_.batch();
    DiscardOnThrow guard(batch);
    // At most kMaxTargetPixels (set_target): the mask shader's pixel count leaves its top bit free.
    const std::size_t pixels = std::size_t(t.width) * t.height, words = (pixels + 31) / 32;
    const std::shared_ptr<void> frame =
        core_.render(device_map(), camera, RenderSettings{}, nullptr, RasterizerCore::Download::kNone);
    const RasterizerCore::Images images = core_.images(frame);
    coverage_keys_.reserve(pixels * 4);
    coverage_select_state_.reserve(io::kCoverageSelectWords * 4);
    coverage_histogram_bins_.reserve(io::kCoverageBins * 4);
    verdicts_.reserve(words * 4);
    batch.fill_zero(coverage_select_state_, io::kCoverageSelectWords * 4);
    batch.fill_zero(coverage_histogram_bins_, io::kCoverageBins * 4);
    batch.fill_zero(verdicts_, words * 4);
    const uint32_t n = uint32_t(pixels), alpha = std::bit_cast<uint32_t>(test.densify_alpha);
    batch.dispatch(coverage_errors_, {images.alpha, images.depth_normalized, &t.depth, &coverage_keys_, &coverage_select_state_},
                   {n, alpha}, groups_for(pixels));
    // The median by radix selection, from the top bits down; it never leaves the device.
    for (int shift = 32 - int(io::kCoverageBits); shift >= 0; shift -= int(io::kCoverageBits)) {
      batch.dispatch(coverage_histogram_, {&coverage_keys_, &coverage_select_state_, &coverage_histogram_bins_},
                     {n, uint32_t(shift)}, groups_for(pixels));
      batch.dispatch(coverage_select_, {&coverage_select_state_, &coverage_histogram_bins_}, {uint32_t(shift)}, 1);
    }
    batch.dispatch(coverage_mask_,
                   {images.alpha, images.depth_normalized, &t.depth, t.ignoring ? &t.ignore : &t.depth,
                    &coverage_select_state_, &verdicts_},
                   {n | (t.ignoring ? 0x80000000u : 0u), alpha, std::bit_cast<uint32_t>(test.depth_error_factor),
                    std::bit_cast<uint32_t>(test.min_median)},
                   groups_for(pixels));
    std::vector<uint32_t> packed(words);
    batch.download(verdicts_, packed.data(), words * 4);
    batch.run();
    std::vector<uint8_t> mask(pixels);
    for (std::size_t p = 0; p < pixels; ++p) mask[p] = uint8_t((packed[p / 32] >> (p % 32)) & 1u);
    return mask;
  }

  std::vector<uint8_t> faint_or_oversized(float min_opacity_logit, float max_log_scale) override {
    if (count_ == 0) return {};
    auto lock = core_.lock();
    CommandBatch& batch = core_.batch();
    const std::size_t words = (count_ + 31) / 32;
    verdicts_.reserve(words * 4);
    batch.fill_zero(verdicts_, words * 4);
    batch.dispatch(prune_flags_, {&arrays_[kLogScales], &arrays_[kOpacity], &verdicts_},
                   {uint32_t(count_), std::bit_cast<uint32_t>(min_opacity_logit), std::bit_cast<uint32_t>(max_log_scale)},
                   groups_for(count_));
    std::vector<uint32_t> packed(words);
    batch.download(verdicts_, packed.data(), words * 4);
    batch.run();
    std::vector<uint8_t> flags(count_);
    for (std::size_t i = 0; i < count_; ++i) flags[i] = uint8_t((packed[i / 32] >> (i % 32)) & 1u);
    return flags;
  }

  void set_target(uint64_t key, const RgbdFrame& frame) override {
    frame.camera.validate("resident map target");
    const std::size_t pixels = std::size_t(frame.width()) * frame.height();
    if (pixels > kMaxTargetPixels) {
      throw Error("resident map target: " + std::to_string(frame.width()) + "x" + std::to_string(frame.height()) +
                  " pixels, at most " + std::to_string(kMaxTargetPixels) + " (the loss's workgroups)");
    }
    if (frame.rgb.size() != pixels * 3 || frame.depth.size() != pixels || (!frame.ignore.empty() && frame.ignore.size() != pixels)) {
      throw Error("resident map target: colour, depth or ignore mask does not match the " + std::to_string(frame.width()) + "x" +
                  std::to_string(frame.height()) + " camera");
    }
    auto lock = core_.lock();
    DiscardOnThrow guard(core_.batch());
    auto [it, inserted] = targets_.try_emplace(key, context_);
    Target& t = it->second;
    t.width = frame.width();
    t.height = frame.height();
    t.ignoring = !frame.ignore.empty();
    t.measured = 0;
    std::vector<uint32_t> ignore;
    if (t.ignoring) ignore.assign(frame.ignore.begin(), frame.ignore.end());
    for (std::size_t p = 0; p < pixels; ++p) t.measured += frame.depth[p] > 0 && (!t.ignoring || !frame.ignore[p]);
    t.rgb.reserve(pixels * 3 * 4);
    t.depth.reserve(pixels * 4);
    CommandBatch& batch = core_.batch();
    batch.upload(t.rgb, frame.rgb.data(), pixels * 3 * 4);
    batch.upload(t.depth, frame.depth.data(), pixels * 4);
    if (t.ignoring) {
      t.ignore.reserve(pixels * 4);
      batch.upload(t.ignore, ignore.data(), pixels * 4);
    }
    batch.run();
  }

  void drop_target(uint64_t key) override {
    auto lock = core_.lock();
    targets_.erase(key);
  }
  bool has_target(uint64_t key) const override { return targets_.count(key) != 0; }

  ForwardResult render(const Camera& camera, const RenderSettings& settings, bool coverage_only) override {
    if (count_ == 0) throw Error("resident map: render of an empty map");
    auto lock = core_.lock();
    ForwardResult f;
    core_.render(device_map(), camera, settings, &f,
                 coverage_only ? RasterizerCore::Download::kCoverage : RasterizerCore::Download::kImages);
    return f;
  }

  MappingStepResult step(uint64_t key, const Camera& camera, const MappingLoss& loss, const AdamRates& rates,
                         double lr_scale, bool isotropic) override {
    if (count_ == 0) throw Error("resident map: mapping step on an empty map");
    const Target& t = target(key, camera);
    auto lock = core_.lock();
    CommandBatch& batch = core_.batch();
    DiscardOnThrow guard(batch);
    const std::size_t pixels = std::size_t(t.width) * t.height;
    d_rgb_.reserve(pixels * 3 * 4);
    d_alpha_.reserve(pixels * 4);
    d_depth_.reserve(pixels * 4);
    adam_params_.reserve(sizeof(io::AdamParams));
    const std::shared_ptr<void> frame =
        core_.render(device_map(), camera, RenderSettings{}, nullptr, RasterizerCore::Download::kNone);
    const RasterizerCore::Images images = core_.images(frame);
    loss_.record(batch,
                 {images.rgb, images.alpha, images.depth, &t.rgb, &t.depth, t.ignoring ? &t.ignore : nullptr, &d_rgb_,
                  &d_alpha_, &d_depth_},
                 camera, loss, t.measured);
    const RasterizerCore::Gradients grads = core_.record_backward(frame, d_rgb_, d_alpha_, d_depth_, pose_sums_);
    io::AdamParams p{};
    p.lr_means = float(rates.means * lr_scale);
    p.lr_log_scales = float(rates.log_scales * lr_scale);
    p.lr_rotations = float(rates.rotations * lr_scale);
    p.lr_opacity = float(rates.opacity_logits * lr_scale);
    p.lr_sh_dc = float(rates.sh_dc * lr_scale);
    p.lr_sh_rest = float(rates.sh_rest * lr_scale);
    p.beta1 = rates.hyper.beta1;
    p.beta2 = rates.hyper.beta2;
    p.eps = float(rates.hyper.eps);
    p.count = uint32_t(count_);
    p.sh_floats = uint32_t(sh_floats());
    p.isotropic = isotropic ? 1u : 0u;
    batch.upload(adam_params_, &p, sizeof(p));
    batch.dispatch(adam_,
                   {&adam_params_, &arrays_[kMeans], &arrays_[kLogScales], &arrays_[kRotations], &arrays_[kOpacity],
                    &arrays_[kSh], grads.geometry, grads.sh, &arrays_[kMGeometry], &arrays_[kVGeometry], &arrays_[kMSh],
                    &arrays_[kVSh], &arrays_[kSteps]},
                   {}, groups_for(count_));
    batch.run();
    const MappingLossKernels::Result value = loss_.result();
    MappingStepResult out;
    out.loss = value.loss;
    out.d_loss_d_vignetting = value.d_vignetting;
    out.d_loss_d_pose = core_.pose_gradient(pose_sums_, camera);
    return out;
  }

 private:
  std::size_t sh_floats() const { return std::size_t(sh_coeff_count(sh_degree_)) * 3; }
  std::size_t width(int array) const {
    switch (array) {
      case kMeans: case kLogScales: return 3;
      case kRotations: return 4;
      case kOpacity: case kSteps: return 1;
      case kMGeometry: case kVGeometry: return io::kGeometryFloats;
      default: return sh_floats();  // kSh, kMSh, kVSh
    }
  }
  static int array_of(ParamGroup group) {
    switch (group) {
      case ParamGroup::kMeans: return kMeans;
      case ParamGroup::kLogScales: return kLogScales;
      case ParamGroup::kRotations: return kRotations;
      case ParamGroup::kOpacityLogits: return kOpacity;
      case ParamGroup::kSh: break;
    }
    return kSh;
  }
  void check_degree(int degree, const char* what) const {
    if (degree != sh_degree_) {
      throw Error(std::string("resident map ") + what + ": SH degree " + std::to_string(degree) + ", the map's is " +
                  std::to_string(sh_degree_));
    }
  }
  // The frame stored under `key`; throws unless there is one of the camera's size.
  const Target& target(uint64_t key, const Camera& camera) const {
    auto found = targets_.find(key);
    if (found == targets_.end()) throw Error("resident map: no target frame " + std::to_string(key));
    const Target& t = found->second;
    if (camera.width != t.width || camera.height != t.height) {
      throw Error("resident map: a " + std::to_string(camera.width) + "x" + std::to_string(camera.height) +
                  " camera for a " + std::to_string(t.width) + "x" + std::to_string(t.height) + " target");
    }
    return t;
  }
  DeviceMap device_map() const {
    return {&arrays_[kMeans], &arrays_[kLogScales], &arrays_[kRotations], &arrays_[kOpacity], &arrays_[kSh],
            uint32_t(count_), sh_degree_};
  }
  void download(CommandBatch& batch, int array, std::vector<float>& out) {
    out.resize(count_ * width(array));
    batch.download(arrays_[array], out.data(), out.size() * 4);
  }
  // Moments in the gradient layout ([N, kGeometryFloats]) into the map layout.
  static void split_geometry(const std::vector<float>& rows, Gaussians& into) {
    for (std::size_t i = 0; i < into.size(); ++i) {
      const float* r = &rows[i * io::kGeometryFloats];
      for (int k = 0; k < 3; ++k) into.means[i * 3 + k] = r[k], into.log_scales[i * 3 + k] = r[3 + k];
      for (int k = 0; k < 4; ++k) into.rotations[i * 4 + k] = r[6 + k];
      into.opacity_logits[i] = r[10];
    }
  }
  static std::vector<float> join_geometry(const Gaussians& from) {
    std::vector<float> rows(from.size() * io::kGeometryFloats);
    for (std::size_t i = 0; i < from.size(); ++i) {
      float* r = &rows[i * io::kGeometryFloats];
      for (int k = 0; k < 3; ++k) r[k] = from.means[i * 3 + k], r[3 + k] = from.log_scales[i * 3 + k];
      for (int k = 0; k < 4; ++k) r[6 + k] = from.rotations[i * 4 + k];
      r[10] = from.opacity_logits[i];
    }
    return rows;
  }

  // Writes `rows` from row `first` on (the rows before it are kept, growing buffers copy them),
  // with their moments or zero ones; the caller holds the lock.
  void write_rows(const Gaussians& rows, const AdamMoments* moments, std::size_t first) {
    CommandBatch& batch = core_.batch();
    const std::size_t total = first + rows.size();
    std::vector<Buffer> grown;
    std::vector<int> grown_arrays;
    for (int a = 0; a < kArrays; ++a) {
      const std::size_t needed = std::max<std::size_t>(total, 1) * width(a) * 4;
      if (needed <= arrays_[a].capacity()) continue;
      grown.emplace_back(context_);
      grown.back().reserve(needed + needed / 2);  // room to append without a copy every keyframe
      batch.copy(arrays_[a], grown.back(), first * width(a) * 4);
      grown_arrays.push_back(a);
    }
    batch.run();  // the copies must finish before the old buffers go
    for (std::size_t g = 0; g < grown.size(); ++g) arrays_[grown_arrays[g]] = std::move(grown[g]);
    for (ParamGroup group : kAllParamGroups) {
      const int a = array_of(group);
      const std::vector<float>& values = param_group(rows, group);
      batch.upload(arrays_[a], values.data(), values.size() * 4, first * width(a) * 4);
    }
    std::vector<float> m_geometry, v_geometry;
    if (moments) {
      m_geometry = join_geometry(moments->m);
      v_geometry = join_geometry(moments->v);
      batch.upload(arrays_[kMGeometry], m_geometry.data(), m_geometry.size() * 4);
      batch.upload(arrays_[kVGeometry], v_geometry.data(), v_geometry.size() * 4);
      batch.upload(arrays_[kMSh], moments->m.sh.data(), moments->m.sh.size() * 4);
      batch.upload(arrays_[kVSh], moments->v.sh.data(), moments->v.sh.size() * 4);
      batch.upload(arrays_[kSteps], moments->steps.data(), moments->steps.size() * 4);
    } else {
      for (int a : {kMGeometry, kVGeometry, kMSh, kVSh, kSteps}) {
        batch.fill_zero(arrays_[a], rows.size() * width(a) * 4, first * width(a) * 4);
      }
    }
    batch.run();
    count_ = total;
  }

  RasterizerCore& core_;
  Context& context_;
  int sh_degree_;
  std::size_t count_ = 0;
  Kernel adam_, compact_flags_, compact_, free_space_, prune_flags_;
  Kernel coverage_errors_, coverage_histogram_, coverage_select_, coverage_mask_;
  MappingLossKernels loss_;
  std::vector<Buffer> arrays_;  // indexed by Array
  Buffer adam_params_, keep_bits_, offsets_, test_params_, verdicts_;
  Buffer coverage_keys_, coverage_select_state_, coverage_histogram_bins_;
  Buffer d_rgb_, d_alpha_, d_depth_;
  double pose_sums_[io::kPosePartials] = {};
  std::map<uint64_t, Target> targets_;
};

}  // namespace

std::unique_ptr<ResidentMap> make_resident_map(RasterizerCore& core, int sh_degree) {
  return std::make_unique<VulkanResidentMap>(core, sh_degree);
}

}  // namespace splat::vk
