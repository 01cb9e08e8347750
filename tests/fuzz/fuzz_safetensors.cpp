// safetensors files (the golden-vector reader in tests/support).
#include "fuzz_input.h"
#include <stdexcept>

#include "support/safetensors.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  try {
    gslam::test::read_safetensors(gslam::fuzz::write_input("case.safetensors", data, size));
  } catch (const std::runtime_error&) {  // this reader's one error type
  }
  return 0;
}
