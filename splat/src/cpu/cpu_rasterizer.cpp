#include "heap_tuning.h"
#include "splat/cpu_reference.h"
#include "splat/rasterizer.h"

namespace splat {
namespace {

class CpuRasterizer final : public Rasterizer {
 public:
  explicit CpuRasterizer(const CpuOptions& options) : pool_(options.threads) {
    keep_freed_frame_memory();
  }

  std::string name() const override {
    return "cpu (" + std::to_string(pool_.size()) + " threads)";
  }

  ForwardResult forward(const GaussiansView& gaussians, const Camera& camera,
                        const RenderSettings& settings) override {
    return reference_forward(gaussians, camera, settings, pool_, &stage_times_);
  }

  BackwardResult backward(const ForwardResult& forward, const ImageGrads& d_image) override {
    return reference_backward(forward, d_image, pool_, &scratch_, &stage_times_);
  }

  void pose_jacobian(const ForwardResult& forward, std::vector<float>& jacobian) override {
    reference_pose_jacobian(forward, pool_, jacobian, &stage_times_);
  }

  std::map<std::string, double> stage_times_ms() const override { return stage_times_; }
  void reset_stage_times() override { stage_times_.clear(); }
  ThreadPool* host_threads() override { return &pool_; }

 private:
  ThreadPool pool_;
  BackwardScratch<float> scratch_;
  StageTimes stage_times_;
};

}  // namespace

std::unique_ptr<Rasterizer> make_cpu_rasterizer(const CpuOptions& options) {
  return std::make_unique<CpuRasterizer>(options);
}

}  // namespace splat
