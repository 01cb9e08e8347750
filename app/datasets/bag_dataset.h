// A ROS recording (ROS 1 .bag, MCAP) as a Dataset: open_dataset() calls this for such a file.
#pragma once
#include <filesystem>

#include "datasets/dataset.h"

namespace app {

// The colour and depth topics of the recording: options.color_topic / depth_topic, else found by
// message type and encoding (colour: sensor_msgs/Image in rgb8, bgr8, rgba8, bgra8, mono8, or a
// CompressedImage; depth: Image in 16UC1 millimetres or 32FC1 metres), preferring colour over
// mono8. Colour and depth are paired by header stamp as TUM's tools do (associate(), 0.02 s).
// Intrinsics from the CameraInfo beside the colour topic (its namespace), else the only one, else
// options.intrinsics (open_dataset() applies them over it); depth scale by the encoding unless
// options.depth_scale. Entries name the file as rgb and depth; Dataset::store reads their pixels,
// one message at a time. With options.gt_frames "PARENT,CHILD" the ground truth is CHILD's pose in
// PARENT from the recording's /tf and /tf_static, chained through intermediate frames, each
// transform the one nearest the frame's stamp within 0.02 s (static ones at any time); otherwise
// open_dataset() reads groundtruth.txt beside the file. --max-frames is applied by open_dataset().
// Throws splat::Error naming the file: unreadable, no or several candidate topics (listing
// them), encodings gslam does not read or that change along a topic, no camera.
Dataset open_bag(const std::filesystem::path& path, const DatasetOptions& options);

}  // namespace app
