// SLAM configuration JSON (io/slam_config_io.h).
#include "fuzz_input.h"
#include "io/slam_config_io.h"
#include "splat/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  try {
    app::load_slam_config(gslam::fuzz::write_input("config.json", data, size));
  } catch (const splat::Error&) {
  }
  return 0;
}
