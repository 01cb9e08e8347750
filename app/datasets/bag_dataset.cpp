#include "datasets/bag_dataset.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <sstream>

#include "datasets/bag_reader.h"
#include "datasets/ros_image_decode.h"
#include "io/file_error.h"
#include "splat/error.h"

namespace app {

bool is_bag_file(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".bag" || ext == ".mcap";
}

namespace {

// Frame i of the dataset: colour message pairs[i].first and depth message pairs[i].second.
class BagFrameStore final : public FrameStore {
 public:
  BagFrameStore(std::shared_ptr<const BagReader> reader, std::string colour, std::string depth,
                std::vector<std::pair<std::size_t, std::size_t>> pairs)
      : reader_(std::move(reader)),
        colour_(std::move(colour)),
        depth_(std::move(depth)),
        pairs_(std::move(pairs)) {}

  splat::RgbdFrame load(std::size_t i, const splat::Camera& intrinsics,
                        double depth_scale) const override {
    const auto [c, d] = pairs_.at(i);
    const std::string colour_where = where(colour_, c), depth_where = where(depth_, d);
    return rgbd_frame_from_ros(reader_->read_image(colour_, c), reader_->read_image(depth_, d), intrinsics,
                               depth_scale, colour_where, depth_where);
  }

 private:
  std::string where(const std::string& topic, std::size_t k) const {
    return reader_->path().string() + ": " + topic + " message " + std::to_string(k);
  }
  std::shared_ptr<const BagReader> reader_;
  std::string colour_, depth_;
  std::vector<std::pair<std::size_t, std::size_t>> pairs_;
};

bool is_image_type(const std::string& type) {
  return type == "sensor_msgs/Image" || type == "sensor_msgs/CompressedImage";
}

std::string describe_topics(const std::vector<BagTopic>& topics) {
  std::string out;
  for (const auto& t : topics) {
    out += (out.empty() ? "" : ", ") + t.name + " (" + (t.type.empty() ? "no type" : t.type) +
           ", " + std::to_string(t.messages) + " messages)";
  }
  return out.empty() ? "none" : out;
}

// "/camera/rgb/image_color" -> "/camera/rgb/".
std::string namespace_of(const std::string& topic) { return topic.substr(0, topic.rfind('/') + 1); }

struct Chosen {
  std::string topic;
  std::vector<RosImage> index;
};

// The colour (want_depth false) or depth topic: the named one, else the only candidate.
Chosen choose_topic(const BagReader& bag, const std::vector<BagTopic>& topics,
                    const std::string& named, bool want_depth) {
  const std::filesystem::path& path = bag.path();
  const char* what = want_depth ? "depth" : "colour";
  const char* option = want_depth ? "--depth-topic" : "--color-topic";
  const std::string wanted = want_depth ? "sensor_msgs/Image in 16UC1 (mm) or 32FC1 (m)"
                                        : "sensor_msgs/Image in rgb8, bgr8, rgba8, bgra8 or mono8, "
                                          "or sensor_msgs/CompressedImage";
  const auto fits = [&](const RosImage& h) {
    return want_depth ? is_depth_encoding(h) : is_colour_encoding(h);
  };
  const auto label = [](const RosImage& h) {
    return (h.compressed ? "compressed " : "") + h.encoding;
  };
  Chosen chosen;
  if (!named.empty()) {
    const auto t = std::find_if(topics.begin(), topics.end(),
                                [&](const BagTopic& x) { return x.name == named; });
    if (t == topics.end())
      fail(path, std::string(option) + " " + named +
                     ": no such topic; its topics: " + describe_topics(topics));
    if (!is_image_type(t->type))
      fail(path, std::string(option) + " " + named + " holds " + t->type + ", expected " + wanted);
    chosen.topic = named;
  } else {
    std::vector<std::string> candidates, preferred;
    for (const auto& t : topics) {
      if (!is_image_type(t.type) || t.messages == 0) continue;
      const std::optional<RosImage> first = bag.first_image(t.name);
      if (!first || !fits(*first)) continue;
      candidates.push_back(t.name);
      // Colour over grey: a camera's image_color beside its image_mono.
      if (want_depth || first->compressed || first->encoding != "mono8")
        preferred.push_back(t.name);
    }
    if (!preferred.empty()) candidates = preferred;
    if (candidates.empty())
      fail(path, std::string("no ") + what + " topic (" + wanted +
                     "); its topics: " + describe_topics(topics));
    if (candidates.size() > 1) {
      std::string list;
      for (const auto& c : candidates) list += (list.empty() ? "" : ", ") + c;
      fail(path,
           std::string("several ") + what + " topics (" + list + "): choose one with " + option);
    }
    chosen.topic = candidates.front();
  }
  chosen.index = bag.image_index(chosen.topic);
  if (chosen.index.empty()) fail(path, chosen.topic + " has no messages");
  const RosImage& first = chosen.index.front();
  for (std::size_t k = 0; k < chosen.index.size(); ++k) {
    const RosImage& h = chosen.index[k];
    if (!fits(h)) {
      fail(path, chosen.topic + " message " + std::to_string(k) + ": encoding '" + label(h) +
                     "' is not a " + what + " encoding gslam reads (" + wanted + ")");
    }
    // One depth unit and one image size along a topic.
    if (h.encoding != first.encoding && want_depth) {
      fail(path, chosen.topic + " message " + std::to_string(k) + ": encoding '" + h.encoding +
                     "', message 0 '" + first.encoding + "' (one depth encoding per topic)");
    }
    if (!h.compressed && (h.width != first.width || h.height != first.height)) {
      fail(path, chosen.topic + " message " + std::to_string(k) + ": " + std::to_string(h.width) +
                     "x" + std::to_string(h.height) + ", message 0 " + std::to_string(first.width) +
                     "x" + std::to_string(first.height));
    }
  }
  return chosen;
}

// --gt-frames "world,kinect": each entry's pose of the child frame in the parent frame from the
// recording's transforms, chained child -> its parent -> ... -> parent.
void attach_tf_ground_truth(Dataset& d, const BagReader& bag, const std::string& gt_frames) {
  const std::filesystem::path& path = bag.path();
  const auto comma = gt_frames.find(',');
  const auto frame = [](std::string id) { return id.empty() || id[0] != '/' ? id : id.substr(1); };
  const std::string world = frame(gt_frames.substr(0, comma));
  const std::string camera = comma == std::string::npos ? "" : frame(gt_frames.substr(comma + 1));
  if (world.empty() || camera.empty() || camera.find(',') != std::string::npos) {
    throw splat::Error("--gt-frames '" + gt_frames +
                       "': expected PARENT,CHILD (e.g. world,kinect)");
  }
  struct Edge {
    std::string parent;
    std::vector<RosTransform> samples;  // by stamp
  };
  std::map<std::string, Edge> edges;  // by child frame
  for (const RosTransform& t : bag.transforms()) {
    Edge& e = edges[t.child];
    if (e.samples.empty()) e.parent = t.parent;
    if (e.parent == t.parent) e.samples.push_back(t);  // a frame has one parent in a tf tree
  }
  for (auto& [child, e] : edges) {
    std::stable_sort(
        e.samples.begin(), e.samples.end(),
        [](const RosTransform& x, const RosTransform& y) { return x.stamp < y.stamp; });
  }
  std::vector<const Edge*> chain;  // camera's edge first
  for (std::string f = camera; f != world;) {
    const auto it = edges.find(f);
    if (it == edges.end() || chain.size() > edges.size()) {
      std::string known;
      for (const auto& [child, e] : edges)
        known += (known.empty() ? "" : ", ") + e.parent + " -> " + child;
      fail(path, "--gt-frames " + gt_frames + ": no chain of transforms from " + world + " to " +
                     camera + " in /tf, /tf_static (" +
                     (known.empty() ? std::string("none there") : known) + ")");
    }
    chain.push_back(&it->second);
    f = it->second.parent;
  }
  const auto at = [&path](const Edge& e, double t) -> std::optional<Eigen::Isometry3d> {
    const auto& s = e.samples;
    auto it = std::lower_bound(s.begin(), s.end(), t,
                               [](const RosTransform& x, double v) { return x.stamp < v; });
    const RosTransform* best = nullptr;
    if (it != s.end()) best = &*it;
    if (it != s.begin() && (!best || t - std::prev(it)->stamp < best->stamp - t))
      best = &*std::prev(it);
    if (!best) return std::nullopt;
    // Within 0.02 s, as TUM's associate.py pairs poses with frames; static transforms always.
    if (!best->is_static && std::abs(best->stamp - t) > 0.02) return std::nullopt;
    const auto& q = best->rotation;
    const Eigen::Quaterniond rotation(q[3], q[0], q[1], q[2]);
    const Eigen::Vector3d translation(best->translation[0], best->translation[1],
                                      best->translation[2]);
    if (!(rotation.norm() > 1e-6) || !std::isfinite(rotation.norm()) || !translation.allFinite()) {
      throw splat::Error(path.string() + ": /tf transform " + best->parent + " -> " + best->child +
                         " at " + std::to_string(best->stamp) +
                         " s is not a pose (zero or non-finite quaternion, or "
                         "non-finite translation)");
    }
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = rotation.normalized().toRotationMatrix();
    T.translation() = translation;
    return T;
  };
  std::size_t found = 0;
  for (DatasetEntry& entry : d.entries) {
    Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
    bool complete = true;
    for (auto e = chain.rbegin(); e != chain.rend() && complete; ++e) {
      const auto T = at(**e, entry.timestamp);
      if (T) T_world_camera = T_world_camera * *T;
      complete = T.has_value();
    }
    if (complete) entry.T_world_cam_truth = T_world_camera, ++found;
  }
  if (found == 0 && !d.entries.empty()) {
    d.warnings.push_back(
        path.string() + ": --gt-frames " + gt_frames +
        ": no transform within 0.02 s of any frame; the frames have no ground truth");
  }
}

}  // namespace

Dataset open_bag(const std::filesystem::path& path, const DatasetOptions& options) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  std::shared_ptr<const BagReader> bag = ext == ".mcap" ? open_mcap(path) : open_ros1_bag(path);
  const std::vector<BagTopic> topics = bag->topics();
  const Chosen colour = choose_topic(*bag, topics, options.color_topic, false);
  const Chosen depth = choose_topic(*bag, topics, options.depth_topic, true);
  if (colour.topic == depth.topic) fail(path, "colour and depth are one topic, " + colour.topic);

  Dataset d;
  d.format = ext == ".mcap" ? "mcap" : "rosbag";
  d.root = path;
  d.depth_scale =
      options.depth_scale > 0 ? options.depth_scale : default_depth_scale(depth.index.front());

  // The camera: CameraInfo in the colour topic's namespace, else the only CameraInfo topic.
  std::vector<std::string> infos;
  std::string info_topic;
  for (const auto& t : topics) {
    if (t.type != "sensor_msgs/CameraInfo" || t.messages == 0) continue;
    infos.push_back(t.name);
    if (namespace_of(t.name) == namespace_of(colour.topic)) info_topic = t.name;
  }
  if (info_topic.empty() && infos.size() == 1) info_topic = infos.front();
  std::optional<RosCameraInfo> info;
  if (!info_topic.empty()) info = bag->camera_info(info_topic);
  if (info && is_rectified_topic(colour.topic)) use_rectified_camera(*info);
  if (!options.intrinsics.empty()) {
    // open_dataset() applies them, as for every format.
  } else if (info) {
    const auto& k = info->k;
    if (!(k[0] > 0) || !(k[4] > 0) || !std::isfinite(k[0]) || !std::isfinite(k[4]) ||
        !std::isfinite(k[2]) || !std::isfinite(k[5])) {
      fail(path,
           info_topic + ": camera matrix K has fx " + std::to_string(k[0]) + ", fy " +
               std::to_string(k[4]) +
               " (expected positive, finite); give --intrinsics fx,fy,cx,cy[,k1,k2,p1,p2,k3]");
    }
    d.intrinsics.fx = k[0], d.intrinsics.fy = k[4], d.intrinsics.cx = k[2], d.intrinsics.cy = k[5];
    d.camera_source = path.string() + ": " + info_topic;
    d.distortion = lens_distortion_from_ros(info->distortion_model, info->d, d.camera_source);
  } else {
    fail(path, infos.empty()
                   ? "no sensor_msgs/CameraInfo topic: give --intrinsics fx,fy,cx,cy"
                   : "no CameraInfo beside " + colour.topic + " (" + std::to_string(infos.size()) +
                         " others): give --intrinsics fx,fy,cx,cy");
  }

  // Colour and depth paired by stamp, as TUM's associate.py.
  std::vector<double> colour_t, depth_t;
  for (const auto& h : colour.index) colour_t.push_back(h.stamp);
  for (const auto& h : depth.index) depth_t.push_back(h.stamp);
  const auto pairs = associate(colour_t, depth_t);
  d.listed = colour.index.size();
  d.unmatched = colour.index.size() - pairs.size();
  if (d.unmatched > 0 && 2 * d.unmatched > colour.index.size()) {
    d.warnings.push_back(path.string() + ": " + std::to_string(d.unmatched) + " of " +
                         std::to_string(colour.index.size()) + " colour images on " + colour.topic +
                         " have no depth image on " + depth.topic + " within 0.02 s");
  }
  for (const auto& [c, k] : pairs)
    d.entries.push_back({colour.index[c].stamp, path, path, std::nullopt, depth.index[k].stamp - colour.index[c].stamp});
  if (d.entries.empty()) {
    fail(path, "no frame has both colour and depth (" + std::to_string(colour.index.size()) +
                   " on " + colour.topic + ", " + std::to_string(depth.index.size()) + " on " +
                   depth.topic + ", none within 0.02 s)");
  }

  // Image size: the colour images' (a compressed one is decoded to know it).
  const auto [c0, d0] = pairs.front();
  if (colour.index.front().compressed) {
    const splat::Image8 first =
        decode_colour(bag->read_image(colour.topic, c0), path.string() + ": " + colour.topic);
    d.intrinsics.width = first.width, d.intrinsics.height = first.height;
  } else {
    d.intrinsics.width = static_cast<int>(colour.index.front().width);
    d.intrinsics.height = static_cast<int>(colour.index.front().height);
  }
  // A CameraInfo of another size (the depth camera's, a binned stream's) is not this camera.
  if (info && options.intrinsics.empty() && info->width != 0 &&
      (info->width != std::uint32_t(d.intrinsics.width) ||
       info->height != std::uint32_t(d.intrinsics.height))) {
    fail(path, info_topic + " is for " + std::to_string(info->width) + "x" +
                   std::to_string(info->height) + " images, " + colour.topic + " has " +
                   std::to_string(d.intrinsics.width) + "x" + std::to_string(d.intrinsics.height) +
                   ": give --intrinsics fx,fy,cx,cy[,k1,k2,p1,p2,k3]");
  }
  const RosImage& dh = depth.index[d0];
  if (dh.width != std::uint32_t(d.intrinsics.width) ||
      dh.height != std::uint32_t(d.intrinsics.height)) {
    fail(path, depth.topic + " is " + std::to_string(dh.width) + "x" + std::to_string(dh.height) +
                   ", " + colour.topic + " " + std::to_string(d.intrinsics.width) + "x" +
                   std::to_string(d.intrinsics.height) +
                   " (gslam needs depth registered to colour)");
  }
  d.store = std::make_shared<BagFrameStore>(bag, colour.topic, depth.topic, pairs);
  d.color_topic = colour.topic;
  d.depth_topic = depth.topic;
  d.gt_frames = options.gt_frames;
  if (!options.gt_frames.empty()) attach_tf_ground_truth(d, *bag, options.gt_frames);
  return d;
}

}  // namespace app
