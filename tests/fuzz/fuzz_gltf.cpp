// glTF and GLB maps (io/gltf_io.h): a first byte that is even makes the input a .glb, else a .gltf
// beside a fixed buffer file it may refer to.
#include "fuzz_input.h"
#include "io/gltf_io.h"
#include "splat/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const bool binary = data[0] % 2 == 0;
  static const uint8_t buffer[64] = {};
  gslam::fuzz::write_input("buffer.bin", buffer, sizeof(buffer));
  try {
    app::to_gaussians(app::read_gltf_splats(gslam::fuzz::write_input(binary ? "map.glb" : "map.gltf", data + 1, size - 1)));
  } catch (const splat::Error&) {
  }
  return 0;
}
