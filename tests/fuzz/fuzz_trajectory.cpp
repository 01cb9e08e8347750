// TUM trajectories (io/trajectory.h).
#include "fuzz_input.h"
#include "io/trajectory.h"
#include "splat/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  try {
    app::read_tum_trajectory(gslam::fuzz::write_input("trajectory.txt", data, size));
  } catch (const splat::Error&) {
  }
  return 0;
}
