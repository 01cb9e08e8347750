// PLY maps (io/ply_io.h).
#include "fuzz_input.h"
#include "io/ply_io.h"
#include "splat/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  try {
    app::read_ply(gslam::fuzz::write_input("map.ply", data, size));
  } catch (const splat::Error&) {
  }
  return 0;
}
