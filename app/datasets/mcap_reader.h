// MCAP (https://mcap.dev/spec), the container `ros2 bag record` writes by default, read without
// any ROS library: records, chunks (uncompressed, zstd, lz4), schemas and channels, and the
// messages gslam takes from it (sensor_msgs Image, CompressedImage, CameraInfo) decoded from CDR
// (ROS 2) or the ROS 1 serialization. open_mcap() in bag_reader.h is the entry point; this
// header holds the limits it enforces.
#pragma once
#include <cstdint>

namespace app {

// A chunk decompresses into memory whole: larger ones are refused before anything is allocated.
// rosbag2 writes chunks of about 1 MiB, a larger message alone in its chunk; the largest image
// gslam reads (image_size_allowed: 2^26 pixels, 4 bytes each as rgba8 or 32FC1) is 256 MiB.
inline constexpr std::uint64_t kMaxMcapChunkBytes = (std::uint64_t(256) + 16) << 20;
// Schema, channel and CameraInfo records are read whole; they are a few KiB.
inline constexpr std::uint64_t kMaxMcapSmallRecordBytes = std::uint64_t(16) << 20;

}  // namespace app
