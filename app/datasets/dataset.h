#pragma once
#include <Eigen/Geometry>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "datasets/color_registration.h"
#include "datasets/label_images.h"
#include "datasets/lens_distortion.h"
#include "splat/rgbd_frame.h"

namespace app {

struct DatasetOptions {
  // "fx,fy,cx,cy[,k1,k2,p1,p2[,k3]]" overrides the preset (image size from the files); with
  // distortion coefficients the frames are undistorted as they load.
  std::string intrinsics;
  double depth_scale = 0;   // stored value per metre; 0 = the format's default
  int max_frames = 0;       // 0 = all
  std::string color_topic;  // ROS recordings: the colour and depth image topics (default: found
  std::string depth_topic;  // by message type and encoding, datasets/bag_dataset.h)
  std::string gt_frames;    // ROS recordings: "world,kinect", ground truth from /tf (else groundtruth.txt)
  // Label images (datasets/label_images.h); empty: labels/ beside the colour folder, if it holds
  // classes.json.
  std::filesystem::path labels;
  // The colour camera (datasets/color_registration.h): "auto" (estimated; also when empty),
  // "registered", or its "fx,fy,cx,cy".
  std::string color_camera;
};

struct DatasetEntry {
  double timestamp = 0;
  std::filesystem::path rgb, depth;
  std::optional<Eigen::Isometry3d> T_world_cam_truth;  // ground truth, camera to world
  double depth_offset = 0;  // the depth image's timestamp minus the colour image's, seconds
};

// Frames kept inside one file (a ROS bag, an MCAP file) rather than as image files: entry i of a
// Dataset with a store is the store's frame i.
class FrameStore {
 public:
  virtual ~FrameStore() = default;
  // Frame i: colour [H, W, 3] / 255, depth [H, W] in metres (stored value / depth_scale), camera
  // `intrinsics`; the timestamp is left to Dataset::load. Safe to call from several threads.
  // Throws splat::Error naming the file and the message for unreadable or mis-sized images.
  virtual splat::RgbdFrame load(std::size_t i, const splat::Camera& intrinsics, double depth_scale) const = 0;
};

// An RGB-D sequence on disk: entries in time order, loaded one frame at a time.
struct Dataset {
  std::string format;  // "tum" (the plain folder too), "images", "replica", "rosbag", "mcap"; "watched" for live --watch
  std::filesystem::path root;  // the folder, or the recording file
  // The pinhole camera that load() gives frames in (pose unused): the camera's own, or, when its
  // lens distorts (`distortion`), the one `undistortion` resamples the frames into.
  splat::Camera intrinsics;
  LensDistortion distortion;  // of the raw images; none for rectified ones
  std::string camera_source;  // where the camera came from ("DIR/intrinsics.txt", "--intrinsics",
                              // ...), for errors
  std::shared_ptr<const Undistortion> undistortion;
  // Colour not registered to depth: resampled into `intrinsics`' pixels after undistortion;
  // null where colour is registered (given, or the estimate did not clearly beat it).
  std::shared_ptr<const ColorResampler> color_registration;
  std::optional<ColorCameraEstimate> color_estimate;  // when "auto" estimated it
  double depth_scale = 5000;
  std::vector<DatasetEntry> entries;  // in a recording, rgb and depth both name the file
  std::shared_ptr<const FrameStore> store;  // set for recordings: their frames' pixels
  std::optional<LabelSet> labels;  // the sequence's label images, if it has them
  // Where the listed frames went: listed = entries.size() + missing_colour + unmatched +
  // beyond_max_frames. A folder holding part of a sequence (lists for all of it, images for some)
  // is normal and not a warning.
  std::size_t listed = 0;  // colour frames listed (rgb.txt lines; images in rgb/; Replica frame*.jpg)
  std::size_t missing_colour = 0;  // listed colour frames whose image file does not exist
  std::size_t unmatched = 0;  // colour images present without depth (TUM: none within 0.02 s;
                              // images: no depth/ image of the same stem)
  std::size_t beyond_max_frames = 0;  // frames left out by --max-frames
  std::size_t skipped_missing = 0;    // listed files (colour and depth) that do not exist
  // Real problems found while opening (ground truth matching no frame, most colour images
  // without depth, fewer Replica poses than frames), one line each, for the caller to print.
  std::vector<std::string> warnings;
  // A ROS recording's colour and depth topics as read, and --gt-frames; recorded in a run's
  // summary.json so that eval and --resume read the same frames.
  std::string color_topic, depth_topic, gt_frames;

  // "193 frames used (of 2406 listed; 2206 have no colour image here, 7 no depth within 0.02 s)",
  // or "193 frames" when every listed frame is used.
  std::string frames_used() const;
  // "colour resampled from the colour camera fx,fy,cx,cy (...)" where colour is registered here,
  // else empty.
  std::string color_note() const;

  // Reads entry i (colour /255, depth / depth_scale), from its files or from `store`, with its
  // label image where there is one (pixels of dynamic classes ignored). Throws
  // splat::Error naming the file for unreadable images or a size that does not match the intrinsics.
  splat::RgbdFrame load(std::size_t i) const;
  bool has_ground_truth() const;
};

// Sets the camera's fx, fy, cx, cy from "fx,fy,cx,cy" and returns the lens distortion that may
// follow ("fx,fy,cx,cy,k1,k2,p1,p2[,k3]"; none without); throws splat::Error naming the text.
LensDistortion apply_intrinsics(splat::Camera& camera, const std::string& intrinsics);
// Where `distortion` is some: sets d.distortion and d.undistortion from d.intrinsics (sized),
// and d.intrinsics to the pinhole camera the frames load in. `where` names the camera's source.
void set_lens_distortion(Dataset& d, const LensDistortion& distortion, const std::string& where);
// gslam's intrinsics.txt: "fx fy cx cy" in pixels, optionally followed by the lens distortion
// "k1 k2 p1 p2 [k3]" (OpenCV's order), on one line. Sets the camera's fx, fy, cx, cy and returns
// the distortion (none without); throws splat::Error naming the file.
LensDistortion read_intrinsics_file(splat::Camera& camera, const std::filesystem::path& path);
// The camera and distortion as --intrinsics takes them, "fx,fy,cx,cy[,k1,k2,p1,p2,k3]", exactly.
std::string intrinsics_text(const splat::Camera& camera, const LensDistortion& distortion);
// d.color_registration as `choice` asks: none (registered), the given colour camera, or the one
// estimate_color_camera() finds on up to 8 frames spread over d (d.color_estimate). Call after the
// camera and lens are set.
void set_color_camera(Dataset& d, const ColorCameraChoice& choice);
// d's camera from "fx,fy,cx,cy[,k1,k2,p1,p2[,k3]]", sized as the colour image `rgb`. Throws
// splat::Error naming the text or the file.
void set_camera(Dataset& d, const std::string& intrinsics, const std::filesystem::path& rgb);

// Opens a dataset folder, detecting its format: TUM RGB-D (rgb.txt, depth.txt, optional
// groundtruth.txt; intrinsics preset from freiburg1/2/3 in the folder name, with the fr1 and fr2
// Kinects' lens distortion), the plain folder (the same lists plus intrinsics.txt "fx fy cx cy",
// optionally followed by distortion "k1 k2 p1 p2 [k3]"), a folder of images without lists
// ("images": rgb/NAME.{png,jpg,jpeg} + depth/NAME.png paired by identical stem NAME, intrinsics.txt
// or
// --intrinsics, optional groundtruth.txt, depth / 5000 by default; numeric stems are timestamps in
// seconds and ordered as numbers, otherwise frames are in name order stamped index / 30 s), or
// Replica as used by NICE-SLAM/SplaTAM (results/frameNNNNNN.jpg, results/depthNNNNNN.png / 6553.5,
// traj.txt). An unknown camera without --intrinsics is an error, never a guess. A folder that
// matches no layout is an error naming every layout and what the folder lacks. A file ending in
// .bag (ROS 1) or .mcap (ROS 2's default) is a recording: open_bag() (datasets/bag_dataset.h)
// reads it, with ground truth from groundtruth.txt beside it.
// An image file's stem as its timestamp in seconds ("1341841873.273798", "-2", "1e3"), if all
// of it is one finite number. The images layout and `live --watch` stamp frames alike: by this,
// else at 30 Hz by index.
std::optional<double> stem_number(const std::string& stem);

Dataset open_dataset(const std::filesystem::path& root, const DatasetOptions& options = {});

// TUM's association: each colour frame paired with the nearest unused depth frame within
// max_difference seconds, greedily by smallest difference; returns (colour index, depth index).
std::vector<std::pair<std::size_t, std::size_t>> associate(const std::vector<double>& a,
                                                           const std::vector<double>& b,
                                                           double max_difference = 0.02);

}  // namespace app
