// Run checkpoints (io/run_checkpoint.h), read and then restored into a SLAM system, whose
// consistency checks are the second half of the reader.
#include "fuzz_input.h"
#include "io/run_checkpoint.h"
#include "splat/rasterizer.h"
#include "splat/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  try {
    app::RunCheckpoint c = app::read_run_checkpoint(gslam::fuzz::write_input("checkpoint.bin", data, size));
    static auto rasterizer = splat::make_cpu_rasterizer({1});
    app::SlamSystem slam(*rasterizer, app::SlamConfig{});
    splat::RgbdFrame frame;
    frame.camera.width = 8;
    frame.camera.height = 6;
    frame.camera.fx = frame.camera.fy = 8;
    frame.camera.cx = 4;
    frame.camera.cy = 3;
    frame.rgb.assign(8 * 6 * 3, 0.5f);
    frame.depth.assign(8 * 6, 1.f);
    slam.restore(std::move(c.slam), [&](std::size_t) { return frame; });
  } catch (const splat::Error&) {
  }
  return 0;
}
