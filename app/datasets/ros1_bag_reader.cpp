#include "datasets/ros1_bag_reader.h"

#include "io/file_error.h"

#ifdef GSLAM_HAVE_ROS1
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <tf2_msgs/TFMessage.h>

#include <map>
#include <mutex>
#endif

namespace app {

#ifdef GSLAM_HAVE_ROS1
namespace {

double seconds(const ros::Time& stamp, const ros::Time& recorded) {
  return stamp.isZero() ? recorded.toSec() : double(stamp.sec) + double(stamp.nsec) / 1e9;
}

// A bag's Image or CompressedImage message as gslam's RosImage (data copied when with_data).
RosImage to_image(const rosbag::MessageInstance& m, bool with_data) {
  RosImage out;
  if (const auto image = m.instantiate<sensor_msgs::Image>()) {
    out.stamp = seconds(image->header.stamp, m.getTime());
    out.encoding = image->encoding;
    out.width = image->width;
    out.height = image->height;
    out.step = image->step;
    out.big_endian = image->is_bigendian != 0;
    if (with_data) out.data = image->data;
  } else if (const auto compressed = m.instantiate<sensor_msgs::CompressedImage>()) {
    out.stamp = seconds(compressed->header.stamp, m.getTime());
    out.encoding = compressed->format;
    out.compressed = true;
    if (with_data) out.data = compressed->data;
  } else {
    throw splat::Error(m.getTopic() + " holds " + m.getDataType() + " (md5 " + m.getMD5Sum() +
                       "), not the sensor_msgs/Image or CompressedImage gslam was built with");
  }
  return out;
}

class Ros1BagReader final : public BagReader {
 public:
  explicit Ros1BagReader(const std::filesystem::path& path) : path_(path) {
    guarded([&] {
      bag_.open(path.string(), rosbag::bagmode::Read);
      rosbag::View all(bag_);
      for (const rosbag::ConnectionInfo* c : all.getConnections())
        topics_[c->topic].type = c->datatype;
      for (auto& [name, topic] : topics_) {
        topic.name = name;
        topic.messages = rosbag::View(bag_, rosbag::TopicQuery(name)).size();
      }
    });
  }

  const std::filesystem::path& path() const override { return path_; }

  std::vector<BagTopic> topics() const override {
    std::vector<BagTopic> out;
    for (const auto& [name, topic] : topics_) out.push_back(topic);
    return out;
  }

  std::vector<RosImage> image_index(const std::string& topic) const override {
    std::lock_guard lock(mutex_);
    return indexed(topic).headers;
  }

  // One message read, not the topic: a bag's image topics are told apart before one is indexed.
  std::optional<RosImage> first_image(const std::string& topic) const override {
    std::lock_guard lock(mutex_);
    const auto it = indexes_.find(topic);
    if (it != indexes_.end()) {
      if (it->second.headers.empty()) return std::nullopt;
      return it->second.headers.front();
    }
    std::optional<RosImage> out;
    guarded([&] {
      rosbag::View view(bag_, rosbag::TopicQuery(topic));
      if (view.begin() != view.end()) out = to_image(*view.begin(), false);
    });
    return out;
  }

  RosImage read_image(const std::string& topic, std::size_t k) const override {
    std::lock_guard lock(mutex_);
    const Index& index = indexed(topic);
    RosImage out;
    guarded([&] { out = to_image(index.messages.at(k), true); });
    return out;
  }

  std::vector<RosTransform> transforms() const override {
    std::lock_guard lock(mutex_);
    std::vector<RosTransform> out;
    const auto frame = [](const std::string& id) {
      return id.empty() || id[0] != '/' ? id : id.substr(1);
    };
    guarded([&] {
      for (const auto& [name, topic] : topics_) {
        // tf/tfMessage has tf2_msgs/TFMessage's definition and MD5, so one type reads both.
        if (topic.type != "tf2_msgs/TFMessage" && topic.type != "tf/tfMessage") continue;
        rosbag::View view(bag_, rosbag::TopicQuery(name));
        for (const rosbag::MessageInstance& m : view) {
          const auto tf = m.instantiate<tf2_msgs::TFMessage>();
          if (!tf) continue;
          for (const auto& t : tf->transforms) {
            RosTransform r;
            r.stamp = seconds(t.header.stamp, m.getTime());
            r.parent = frame(t.header.frame_id);
            r.child = frame(t.child_frame_id);
            r.translation = {t.transform.translation.x, t.transform.translation.y,
                             t.transform.translation.z};
            r.rotation = {t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z,
                          t.transform.rotation.w};
            r.is_static = name == "/tf_static";
            out.push_back(r);
          }
        }
      }
    });
    return out;
  }

  std::optional<RosCameraInfo> camera_info(const std::string& topic) const override {
    std::lock_guard lock(mutex_);
    std::optional<RosCameraInfo> out;
    guarded([&] {
      rosbag::View view(bag_, rosbag::TopicQuery(topic));
      for (const rosbag::MessageInstance& m : view) {
        const auto info = m.instantiate<sensor_msgs::CameraInfo>();
        if (!info) continue;
        out.emplace();
        out->width = info->width;
        out->height = info->height;
        for (int i = 0; i < 9; ++i) out->k[std::size_t(i)] = info->K[std::size_t(i)];
        out->distortion_model = info->distortion_model;
        out->d.assign(info->D.begin(), info->D.end());
        for (int i = 0; i < 12; ++i) out->p[std::size_t(i)] = info->P[std::size_t(i)];
        break;
      }
    });
    return out;
  }

 private:
  struct Index {
    std::vector<rosbag::MessageInstance>
        messages;  // point into bag_'s index, valid while it is open
    std::vector<RosImage> headers;
  };

  // Runs f, turning rosbag's exceptions into one line naming the file.
  template <typename F>
  void guarded(F&& f) const {
    try {
      f();
    } catch (const rosbag::BagUnindexedException&) {
      fail(path_, "unindexed ROS 1 bag (recording cut off?): run 'rosbag reindex' on it");
    } catch (const rosbag::BagIOException& e) {
      fail(path_, std::string("truncated or not a ROS 1 bag (") + e.what() +
                      "); a recording cut off may be recovered with 'rosbag reindex'");
    } catch (const rosbag::BagException& e) {
      fail(path_, std::string("not a readable ROS 1 bag: ") + e.what());
    } catch (const ros::Exception& e) {
      fail(path_, std::string("ROS 1 bag: ") + e.what());
    } catch (const splat::Error& e) {
      fail(path_, e.what());
    }
  }

  // The topic's messages, read once (under mutex_).
  const Index& indexed(const std::string& topic) const {
    auto it = indexes_.find(topic);
    if (it != indexes_.end()) return it->second;
    Index index;
    guarded([&] {
      rosbag::View view(bag_, rosbag::TopicQuery(topic));
      for (const rosbag::MessageInstance& m : view) {
        index.headers.push_back(to_image(m, false));
        index.messages.push_back(m);
      }
    });
    return indexes_.emplace(topic, std::move(index)).first->second;
  }

  std::filesystem::path path_;
  mutable rosbag::Bag bag_;
  std::map<std::string, BagTopic> topics_;
  mutable std::mutex mutex_;  // rosbag::Bag reads through one stream
  mutable std::map<std::string, Index> indexes_;
};

}  // namespace

std::unique_ptr<BagReader> open_ros1_bag(const std::filesystem::path& path) {
  return std::make_unique<Ros1BagReader>(path);
}
bool ros1_bag_supported() { return true; }

#else

std::unique_ptr<BagReader> open_ros1_bag(const std::filesystem::path& path) {
  fail(path,
       "this gslam was built without ROS 1 (rosbag): install librosbag-dev libsensor-msgs-dev "
       "(scripts/install_deps.sh) "
       "and rebuild, or convert the bag to MCAP");
}
bool ros1_bag_supported() { return false; }

#endif

}  // namespace app
