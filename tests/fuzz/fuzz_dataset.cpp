// Dataset lists (datasets/dataset.h): the input is a TUM rgb.txt (with a fixed depth.txt and
// groundtruth.txt) when its first byte is even, else a Replica traj.txt.
#include "datasets/dataset.h"
#include "fuzz_input.h"
#include "splat/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  using gslam::fuzz::write_input;
  const auto text = [](const std::string& s) { return reinterpret_cast<const uint8_t*>(s.data()); };
  app::DatasetOptions options;
  options.intrinsics = "525,525,319.5,239.5";
  try {
    if (data[0] % 2 == 0) {
      const std::string depth = "# depth\n1.0 depth/1.png\n1.1 depth/2.png\n";
      const std::string truth = "1.0 0 0 0 0 0 0 1\n1.1 0 0 0.01 0 0 0 1\n";
      write_input("tum/depth.txt", text(depth), depth.size());
      write_input("tum/groundtruth.txt", text(truth), truth.size());
      const auto rgb = write_input("tum/rgb.txt", data + 1, size - 1);
      app::open_dataset(rgb.parent_path(), options);
    } else {
      const std::string frame = "x";
      write_input("replica/results/frame000000.jpg", text(frame), 1);
      write_input("replica/results/depth000000.png", text(frame), 1);
      const auto traj = write_input("replica/traj.txt", data + 1, size - 1);
      app::open_dataset(traj.parent_path(), options);
    }
  } catch (const splat::Error&) {
  }
  return 0;
}
