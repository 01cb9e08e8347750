#include "support/teddy_recording.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "support/test_data.h"

#ifdef GSLAM_HAVE_ROS1
#include "support/ros1_bag_writer.h"
#endif

namespace gslam::test {

app::Dataset open_teddy(int frames, const std::string& intrinsics) {
  app::DatasetOptions o;
  o.max_frames = frames;
  o.intrinsics = intrinsics;
  return app::open_dataset(shared_data(kTeddyFolder), o);
}

std::array<std::uint32_t, 2> ros_time(const std::string& stem) {
  const auto dot = stem.find('.');
  std::string frac = dot == std::string::npos ? "" : stem.substr(dot + 1);
  frac.resize(9, '0');
  return {static_cast<std::uint32_t>(std::stoul(stem.substr(0, dot))), static_cast<std::uint32_t>(std::stoul(frac))};
}

std::array<std::uint32_t, 2> ros_time(const std::filesystem::path& file) { return ros_time(file.stem().string()); }

std::vector<std::uint8_t> colour_bytes(const splat::RgbdFrame& f, bool bgr) {
  std::vector<std::uint8_t> out(f.rgb.size());
  for (std::size_t k = 0; k < f.rgb.size(); ++k) {
    const std::size_t c = k % 3, px = k - c;
    out[k] = static_cast<std::uint8_t>(std::lround(f.rgb[px + (bgr ? 2 - c : c)] * 255.f));
  }
  return out;
}

std::vector<std::uint8_t> float_bytes(const std::vector<float>& v) {
  std::vector<std::uint8_t> out(v.size() * 4);
  std::memcpy(out.data(), v.data(), out.size());
  return out;
}

std::vector<Transform> mocap(const app::Dataset& folder, int first, int count) {
  std::ifstream in(folder.root / "groundtruth.txt");
  const double from = folder.entries[std::size_t(first)].timestamp - 0.1,
               to = folder.entries[std::size_t(first + count - 1)].timestamp + 0.1;
  std::vector<Transform> out;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    std::string stamp;
    Transform tf;
    words >> stamp >> tf.t[0] >> tf.t[1] >> tf.t[2] >> tf.q[0] >> tf.q[1] >> tf.q[2] >> tf.q[3];
    if (std::stod(stamp) < from || std::stod(stamp) > to) continue;
    tf.stamp = ros_time(stamp);
    out.push_back(tf);
  }
  return out;
}

#ifdef GSLAM_HAVE_ROS1
void write_teddy_bag(const app::Dataset& folder, int first, int count, const std::filesystem::path& out) {
  Ros1BagWriter bag(out.string());
  for (int i = first; i < first + count; ++i) {
    const app::DatasetEntry& e = folder.entries[std::size_t(i)];
    const splat::RgbdFrame f = folder.load(std::size_t(i));
    const auto ct = ros_time(e.rgb), dt = ros_time(e.depth);
    if (i == first) bag.camera_info("/camera/rgb/camera_info", ct[0], ct[1], 640, 480, kTeddyK);
    bag.image("/camera/rgb/image_color", ct[0], ct[1], "rgb8", 640, 480, 640 * 3, colour_bytes(f, false));
    bag.image("/camera/depth/image", dt[0], dt[1], "32FC1", 640, 480, 640 * 4, float_bytes(f.depth));
  }
  for (const Transform& tf : mocap(folder, first, count))
    bag.transform("/tf", tf.stamp[0], tf.stamp[1], "/world", "/kinect", tf.t, tf.q);
  const auto t0 = ros_time(folder.entries[std::size_t(first)].rgb);
  bag.transform("/tf_static", t0[0], t0[1], "kinect", "rgb_optical", kMountT, kMountQ);
  bag.close();
}
#endif

}  // namespace gslam::test
