// ROS recordings as MCAP (datasets/mcap_reader.cpp, datasets/bag_dataset.cpp): the input is an
// MCAP file, opened as a dataset (topics found by type, --intrinsics given so that a file
// without CameraInfo still reaches the frames), and every frame is loaded.
#include "datasets/dataset.h"
#include "fuzz_input.h"
#include "splat/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::filesystem::path path = gslam::fuzz::write_input("input.mcap", data, size);
  app::DatasetOptions options;
  options.intrinsics = "525,525,319.5,239.5";
  try {
    const app::Dataset d = app::open_dataset(path, options);
    for (std::size_t i = 0; i < d.entries.size(); ++i) {
      try {
        d.load(i);
      } catch (const splat::Error&) {
      }
    }
  } catch (const splat::Error&) {
  }
  return 0;
}
