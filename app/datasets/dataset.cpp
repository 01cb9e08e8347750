#include "datasets/dataset.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <regex>
#include <sstream>
#include <system_error>
#include <unordered_map>

#include "datasets/bag_dataset.h"
#include "datasets/bag_reader.h"
#include "io/file_error.h"
#include "io/image_io.h"
#include "io/trajectory.h"
#include "splat/error.h"
#include "splat/se3.h"

namespace app {
namespace {

struct ListEntry {
  double timestamp;
  std::string file;
};

// TUM list file: '#' comments, then "timestamp filename" per line.
std::vector<ListEntry> read_list(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) fail(path, "cannot open file");
  std::vector<ListEntry> out;
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    ListEntry e;
    if (!(words >> e.timestamp >> e.file)) fail(path, "line " + std::to_string(line_no) + ": expected 'timestamp filename'");
    out.push_back(e);
  }
  return out;
}

// Image size from the first colour image.
void set_size_from(splat::Camera& cam, const std::filesystem::path& rgb) {
  const splat::Image8 image = read_rgb8(rgb);
  cam.width = image.width;
  cam.height = image.height;
}

// The camera given on the command line (--intrinsics), or by an intrinsics.txt file.
void use_given_intrinsics(Dataset& d, const std::string& text) {
  d.distortion = apply_intrinsics(d.intrinsics, text);
  d.camera_source = "--intrinsics " + text;
}
void use_intrinsics_file(Dataset& d, const std::filesystem::path& file) {
  d.distortion = read_intrinsics_file(d.intrinsics, file);
  d.camera_source = file.string();
}

// Optional `path` (ROOT/groundtruth.txt, a TUM trajectory) associated with d.entries by timestamp
// within 0.02 s, as TUM's tools do. A file matching no frame (another clock) is a warning.
void attach_ground_truth(Dataset& d, const std::filesystem::path& path) {
  if (!std::filesystem::exists(path)) return;
  const std::vector<StampedPose> truth = read_tum_trajectory(path);
  std::vector<double> truth_t, frame_t;
  for (const auto& p : truth) truth_t.push_back(p.timestamp);
  for (const auto& e : d.entries) frame_t.push_back(e.timestamp);
  const auto pairs = associate(frame_t, truth_t);
  for (const auto& [f, g] : pairs) d.entries[f].T_world_cam_truth = truth[g].T_world_cam;
  if (!truth.empty() && !d.entries.empty() && pairs.empty()) {
    d.warnings.push_back(
        path.string() +
        ": no pose within 0.02 s of any frame (another clock?); the frames have no ground truth");
  }
}

Dataset open_tum(const std::filesystem::path& root, const DatasetOptions& options) {
  Dataset d;
  d.format = "tum";
  d.root = root;
  d.depth_scale = options.depth_scale > 0 ? options.depth_scale : 5000.0;
  const std::string name = std::filesystem::absolute(root).string();
  // Calibrated colour cameras of the TUM Kinects (TUM RGB-D dataset documentation): fr1's and
  // fr2's images are raw, with their lens distortion; fr3's are rectified.
  if (!options.intrinsics.empty()) {
    use_given_intrinsics(d, options.intrinsics);
  } else if (std::filesystem::exists(root / "intrinsics.txt")) {
    use_intrinsics_file(d, root / "intrinsics.txt");
  } else if (name.find("freiburg1") != std::string::npos) {
    d.camera_source = "the freiburg1 preset";
    d.intrinsics.fx = 517.306408, d.intrinsics.fy = 516.469215, d.intrinsics.cx = 318.643040,
    d.intrinsics.cy = 255.313989;
    d.distortion = {0.262383, -0.953104, -0.005358, 0.002628, 1.163314};
  } else if (name.find("freiburg2") != std::string::npos) {
    d.camera_source = "the freiburg2 preset";
    d.intrinsics.fx = 520.908620, d.intrinsics.fy = 521.007327, d.intrinsics.cx = 325.141442,
    d.intrinsics.cy = 249.701764;
    d.distortion = {0.231222, -0.784899, -0.003257, -0.000105, 0.917205};
  } else if (name.find("freiburg3") != std::string::npos) {
    d.intrinsics.fx = 535.4, d.intrinsics.fy = 539.2, d.intrinsics.cx = 320.1, d.intrinsics.cy = 247.6;
  } else {
    fail(root, "unknown TUM camera (no freiburg1/2/3 in the path): give --intrinsics fx,fy,cx,cy "
               "or write intrinsics.txt holding 'fx fy cx cy'");
  }
  std::vector<ListEntry> rgb = read_list(root / "rgb.txt"), depth = read_list(root / "depth.txt");
  // Only entries whose files exist take part (the lists may name more frames than are present).
  auto present = [&](std::vector<ListEntry>& list) {
    const std::size_t before = list.size();
    // A name the file system refuses (too long, say) is a missing file, not an exception.
    list.erase(std::remove_if(list.begin(), list.end(),
                              [&](const ListEntry& e) {
                                std::error_code error;
                                return !std::filesystem::exists(root / e.file, error);
                              }),
               list.end());
    return before - list.size();
  };
  d.listed = rgb.size();
  d.missing_colour = present(rgb);
  d.skipped_missing = d.missing_colour + present(depth);
  std::vector<double> rgb_t, depth_t;
  for (const auto& e : rgb) rgb_t.push_back(e.timestamp);
  for (const auto& e : depth) depth_t.push_back(e.timestamp);
  const auto pairs = associate(rgb_t, depth_t);
  d.unmatched = rgb.size() - pairs.size();
  // Most colour images without depth: the lists' clocks or names disagree, not a partial copy.
  if (d.unmatched > 0 && 2 * d.unmatched > rgb.size()) {
    d.warnings.push_back((root / "depth.txt").string() + ": " + std::to_string(d.unmatched) +
                         " of " + std::to_string(rgb.size()) +
                         " colour images have no depth image within 0.02 s");
  }
  for (const auto& [i, j] : pairs) {
    d.entries.push_back({rgb[i].timestamp, root / rgb[i].file, root / depth[j].file, std::nullopt,
                         depth[j].timestamp - rgb[i].timestamp});
  }
  attach_ground_truth(d, root / "groundtruth.txt");
  return d;
}

// Replica as NICE-SLAM and SplaTAM ship it: results/frameNNNNNN.jpg, results/depthNNNNNN.png
// (/ 6553.5), traj.txt with one row-major 4x4 camera-to-world matrix per frame. Frames are
// stamped at 30 Hz from 0. Intrinsics: their Replica camera (1200x680, f = 600).
Dataset open_replica(const std::filesystem::path& root, const DatasetOptions& options) {
  Dataset d;
  d.format = "replica";
  d.root = root;
  d.depth_scale = options.depth_scale > 0 ? options.depth_scale : 6553.5;
  if (!options.intrinsics.empty()) {
    use_given_intrinsics(d, options.intrinsics);
  } else {
    d.intrinsics.fx = d.intrinsics.fy = 600.0;
    d.intrinsics.cx = 599.5;
    d.intrinsics.cy = 339.5;
  }
  std::vector<Eigen::Isometry3d> poses;
  std::ifstream traj(root / "traj.txt");
  if (!traj) fail(root / "traj.txt", "cannot open file");
  std::string line;
  for (int line_no = 1; std::getline(traj, line); ++line_no) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream words(line);
    Eigen::Matrix4d m;
    for (int k = 0; k < 16; ++k) {
      if (!(words >> m(k / 4, k % 4)) || !std::isfinite(m(k / 4, k % 4))) {
        fail(root / "traj.txt", "line " + std::to_string(line_no) + ": expected 16 numbers (a row-major 4x4 matrix)");
      }
    }
    Eigen::Isometry3d pose;
    pose.matrix() = m;
    poses.push_back(splat::orthonormalized(pose));
  }
  for (std::size_t i = 0;; ++i) {
    char rgb[32], depth[32];
    std::snprintf(rgb, sizeof(rgb), "frame%06zu.jpg", i);
    std::snprintf(depth, sizeof(depth), "depth%06zu.png", i);
    const auto rgb_path = root / "results" / rgb, depth_path = root / "results" / depth;
    if (!std::filesystem::exists(rgb_path)) break;
    ++d.listed;
    if (!std::filesystem::exists(depth_path)) {
      ++d.skipped_missing;
      ++d.unmatched;
      continue;
    }
    DatasetEntry e{static_cast<double>(i) / 30.0, rgb_path, depth_path, std::nullopt};
    if (i < poses.size()) e.T_world_cam_truth = poses[i];
    d.entries.push_back(e);
  }
  if (poses.size() < d.listed) {
    d.warnings.push_back((root / "traj.txt").string() + ": " + std::to_string(poses.size()) +
                         " poses for " + std::to_string(d.listed) +
                         " frames; the frames beyond have no ground truth");
  }
  return d;
}

// ".png" for "a.PNG".
std::string lowercase_extension(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

bool is_colour_image(const std::filesystem::path& file) {
  const std::string ext = lowercase_extension(file);
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg";
}

// The images of ROOT/rgb (colour: .png, .jpg, .jpeg) and ROOT/depth (.png), any case of
// extension; one directory listing each, so thousands of files cost two reads of a directory.
// A folder that does not exist lists nothing.
struct ImageFolder {
  std::vector<std::filesystem::path> colour, depth;
};

ImageFolder list_image_folder(const std::filesystem::path& root) {
  ImageFolder out;
  const auto list = [](const std::filesystem::path& dir, bool (*wanted)(const std::filesystem::path&),
                       std::vector<std::filesystem::path>& files) {
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
      std::error_code type_ec;
      if (e.is_regular_file(type_ec) && wanted(e.path())) files.push_back(e.path());
    }
  };
  list(root / "rgb", is_colour_image, out.colour);
  list(root / "depth", [](const std::filesystem::path& f) { return lowercase_extension(f) == ".png"; },
       out.depth);
  return out;
}

// A folder of images as a camera driver writes it for `live --watch`: rgb/NAME.png|jpg and
// depth/NAME.png paired by identical stem NAME, intrinsics.txt "fx fy cx cy [k1 k2 p1 p2 [k3]]" (or
// --intrinsics), optional groundtruth.txt. When every frame's stem is a number it is the timestamp
// in seconds and frames are in numeric order; otherwise frames are in name order, stamped index /
// 30 s.
Dataset open_images(const std::filesystem::path& root, const ImageFolder& folder,
                    const DatasetOptions& options) {
  Dataset d;
  d.format = "images";
  d.root = root;
  d.depth_scale = options.depth_scale > 0 ? options.depth_scale : 5000.0;  // as TUM and --watch
  if (!options.intrinsics.empty()) {
    use_given_intrinsics(d, options.intrinsics);
  } else if (std::filesystem::exists(root / "intrinsics.txt")) {
    use_intrinsics_file(d, root / "intrinsics.txt");
  } else {
    fail(root / "intrinsics.txt",
         "not found: a folder of images (rgb/, depth/) needs the camera, 'fx fy cx cy' in "
         "pixels in this file, or --intrinsics fx,fy,cx,cy");
  }
  // Two files with one stem would make the pairing ambiguous.
  const auto same_stem = [](const std::filesystem::path& dir, const std::filesystem::path& a,
                            const std::filesystem::path& b) {
    fail(dir, a.filename().string() + " and " + b.filename().string() +
                  " have the same name stem; keep one");
  };
  std::unordered_map<std::string, std::filesystem::path> depth_by_stem;
  depth_by_stem.reserve(folder.depth.size());
  for (const auto& p : folder.depth) {
    const auto [it, inserted] = depth_by_stem.emplace(p.stem().string(), p);
    if (!inserted) same_stem(root / "depth", it->second, p);
  }
  struct Frame {
    std::string stem;
    std::optional<double> number;
    std::filesystem::path rgb, depth;
  };
  std::vector<Frame> frames;
  std::unordered_map<std::string, std::filesystem::path> colour_by_stem;
  colour_by_stem.reserve(folder.colour.size());
  for (const auto& p : folder.colour) {
    std::string stem = p.stem().string();
    const auto [it, inserted] = colour_by_stem.emplace(stem, p);
    if (!inserted) same_stem(root / "rgb", it->second, p);
    ++d.listed;
    const auto depth = depth_by_stem.find(stem);
    if (depth == depth_by_stem.end()) {
      ++d.unmatched;
      continue;
    }
    const std::optional<double> number = stem_number(stem);
    frames.push_back({std::move(stem), number, p, depth->second});
  }
  const bool numeric =
      std::all_of(frames.begin(), frames.end(), [](const Frame& f) { return f.number.has_value(); });
  std::sort(frames.begin(), frames.end(), [&](const Frame& a, const Frame& b) {
    if (numeric && *a.number != *b.number) return *a.number < *b.number;
    return a.stem < b.stem;
  });
  d.entries.reserve(frames.size());
  for (std::size_t k = 0; k < frames.size(); ++k) {
    // Without timestamps in the names: 30 Hz, the usual RGB-D camera rate (Replica's convention).
    const double t = numeric ? *frames[k].number : static_cast<double>(k) / 30.0;
    d.entries.push_back({t, frames[k].rgb, frames[k].depth, std::nullopt});
  }
  // Most colour images without depth: the names disagree, not a few frames lost.
  if (d.unmatched > 0 && 2 * d.unmatched > d.listed) {
    d.warnings.push_back((root / "depth").string() + ": " + std::to_string(d.unmatched) + " of " +
                         std::to_string(d.listed) +
                         " colour images in rgb/ have no depth image of the same name");
  }
  attach_ground_truth(d, root / "groundtruth.txt");
  return d;
}

// What a folder that matches no layout has and lacks, for open_dataset's error.
std::string what_is_missing(const std::filesystem::path& root, const ImageFolder& images) {
  namespace fs = std::filesystem;
  const auto has = [&](const char* name) { return fs::exists(root / name); };
  if (has("rgb.txt")) return "has rgb.txt but no depth.txt";
  if (has("depth.txt")) return "has depth.txt but no rgb.txt";
  if (has("traj.txt")) return "has traj.txt but no results/ folder";
  if (fs::is_directory(root / "results")) return "has results/ but no traj.txt";
  const bool rgb_dir = fs::is_directory(root / "rgb"), depth_dir = fs::is_directory(root / "depth");
  if (rgb_dir && !depth_dir) return "has rgb/ but no depth/";
  if (depth_dir && !rgb_dir) return "has depth/ but no rgb/";
  if (rgb_dir && images.colour.empty()) return "has rgb/ and depth/ but no .png or .jpg image in rgb/";
  if (depth_dir) return "has rgb/ and depth/ but no .png image in depth/";
  std::size_t entries = 0, found = 0;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(root, ec)) {
    ++entries;
    found += is_colour_image(e.path());
  }
  if (found > 0) {
    return "has " + std::to_string(found) +
           " image files but no rgb/ and depth/ holding them, nor rgb.txt and depth.txt listing them";
  }
  if (entries == 0) return "is empty";
  return "has none of rgb.txt, depth.txt, rgb/, depth/, traj.txt, results/";
}

}  // namespace

std::vector<std::pair<std::size_t, std::size_t>> associate(const std::vector<double>& a,
                                                           const std::vector<double>& b,
                                                           double max_difference) {
  // Candidate pairs within the window (b is searched around each a by binary search).
  std::vector<std::size_t> b_order(b.size());
  for (std::size_t j = 0; j < b.size(); ++j) b_order[j] = j;
  std::sort(b_order.begin(), b_order.end(), [&](std::size_t x, std::size_t y) { return b[x] < b[y]; });
  struct Candidate {
    double diff;
    std::size_t i, j;
  };
  std::vector<Candidate> candidates;
  for (std::size_t i = 0; i < a.size(); ++i) {
    auto lo = std::lower_bound(b_order.begin(), b_order.end(), a[i] - max_difference, [&](std::size_t j, double t) { return b[j] < t; });
    for (auto it = lo; it != b_order.end() && b[*it] <= a[i] + max_difference; ++it) {
      candidates.push_back({std::abs(a[i] - b[*it]), i, *it});
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
    return x.diff != y.diff ? x.diff < y.diff : (x.i != y.i ? x.i < y.i : x.j < y.j);
  });
  std::vector<uint8_t> used_a(a.size(), 0), used_b(b.size(), 0);
  std::vector<std::pair<std::size_t, std::size_t>> out;
  for (const auto& c : candidates) {
    if (used_a[c.i] || used_b[c.j]) continue;
    used_a[c.i] = used_b[c.j] = 1;
    out.emplace_back(c.i, c.j);
  }
  std::sort(out.begin(), out.end());
  return out;
}

namespace {

// Why the listed frames not used are not: "2209 have no colour image here, 7 no depth ...".
std::string unused_frames(const Dataset& d) {
  std::string out;
  const auto add = [&](std::size_t n, const std::string& why) {
    if (n > 0) out += (out.empty() ? "" : ", ") + std::to_string(n) + why;
  };
  add(d.missing_colour, " have no colour image here");
  add(d.unmatched, d.format == "tum" || d.store ? " no depth within 0.02 s" : " no depth image");
  add(d.beyond_max_frames, " beyond --max-frames");
  return out;
}

}  // namespace

std::string Dataset::frames_used() const {
  const std::string used = std::to_string(entries.size()) + " frames";
  if (entries.size() == listed) return used;
  return used + " used (of " + std::to_string(listed) + " listed; " + unused_frames(*this) + ")";
}

std::string Dataset::color_note() const {
  if (!color_registration) return "";
  std::string note = "colour resampled into the depth camera from the colour camera " +
                     color_registration->color_camera().text();
  if (!color_estimate) return note + " (--color-camera)";
  char found[160];
  std::snprintf(found, sizeof(found), " (not registered to depth: found on %zu depth-edge pixels, edge score %.2fx registered's)",
                color_estimate->edge_points, color_estimate->gain);
  return note + found;
}

bool Dataset::has_ground_truth() const {
  return std::any_of(entries.begin(), entries.end(), [](const DatasetEntry& e) { return e.T_world_cam_truth.has_value(); });
}

splat::RgbdFrame Dataset::load(std::size_t i) const {
  const DatasetEntry& e = entries.at(i);
  if (store) {
    splat::RgbdFrame f = store->load(i, intrinsics, depth_scale);
    f.timestamp = e.timestamp;
    f.depth_time_offset = e.depth_offset;
    if (undistortion) undistortion->apply(f);
    if (color_registration) color_registration->apply(f);
    return f;
  }
  const splat::Image8 rgb = read_rgb8(e.rgb);
  if (rgb.width != intrinsics.width || rgb.height != intrinsics.height) {
    fail(e.rgb, "image is " + std::to_string(rgb.width) + "x" + std::to_string(rgb.height) + ", expected " +
                    std::to_string(intrinsics.width) + "x" + std::to_string(intrinsics.height));
  }
  const splat::Image16 depth = read_png_gray16(e.depth);
  if (depth.width != rgb.width || depth.height != rgb.height) {
    fail(e.depth, "depth is " + std::to_string(depth.width) + "x" + std::to_string(depth.height) + ", colour is " +
                      std::to_string(rgb.width) + "x" + std::to_string(rgb.height));
  }
  splat::RgbdFrame f;
  f.timestamp = e.timestamp;
  f.depth_time_offset = e.depth_offset;
  f.camera = intrinsics;
  f.rgb.resize(rgb.data.size());
  for (std::size_t k = 0; k < rgb.data.size(); ++k) f.rgb[k] = static_cast<float>(rgb.data[k]) / 255.f;
  f.depth.resize(depth.data.size());
  const float inv = static_cast<float>(1.0 / depth_scale);
  for (std::size_t k = 0; k < depth.data.size(); ++k) f.depth[k] = static_cast<float>(depth.data[k]) * inv;
  if (labels) {
    if (std::optional<std::vector<uint16_t>> ids = read_label_image(*labels, e.rgb, f.width(), f.height())) {
      f.labels = std::move(*ids);
      if (std::any_of(labels->classes.begin(), labels->classes.end(), [](const LabelClass& c) { return c.dynamic; })) {
        f.ignore.resize(f.labels.size());
        for (std::size_t k = 0; k < f.labels.size(); ++k) f.ignore[k] = labels->is_dynamic(f.labels[k]);
      }
    }
  }
  if (undistortion) undistortion->apply(f);
  if (color_registration) color_registration->apply(f);
  return f;
}

namespace {

// The camera from "fx fy cx cy [k1 k2 p1 p2 [k3]]" numbers (4, 8 or 9): false when the count or
// the pinhole part is wrong; the distortion's own errors name `what`.
bool camera_from_numbers(splat::Camera& cam, LensDistortion& distortion,
                         const std::vector<double>& k, const std::string& what) {
  const bool ok = (k.size() == 4 || k.size() == 8 || k.size() == 9) && k[0] > 0 && k[1] > 0 &&
                  std::isfinite(k[0]) && std::isfinite(k[1]) && std::isfinite(k[2]) &&
                  std::isfinite(k[3]);
  if (!ok) return false;
  cam.fx = k[0], cam.fy = k[1], cam.cx = k[2], cam.cy = k[3];
  distortion =
      k.size() == 4 ? LensDistortion{} : lens_distortion_from({k.begin() + 4, k.end()}, what);
  return true;
}

}  // namespace

LensDistortion apply_intrinsics(splat::Camera& cam, const std::string& text) {
  const std::vector<double> v = parse_numbers(text, ',', 10);
  LensDistortion distortion;
  // Every item a finite number, here where the text is a command line's.
  const bool finite = std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
  if (!finite || !camera_from_numbers(cam, distortion, v, "intrinsics '" + text + "'")) {
    throw splat::Error(
        "intrinsics '" + text +
        "': expected fx,fy,cx,cy, optionally followed by the distortion k1,k2,p1,p2[,k3]");
  }
  return distortion;
}

LensDistortion read_intrinsics_file(splat::Camera& cam, const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) fail(path, "cannot open file");
  // The numbers may span lines; the file is a few dozen bytes, so a longer one is not a camera.
  std::string text(4096, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (!in.eof()) fail(path, "over 4 KiB: not 'fx fy cx cy [k1 k2 p1 p2 [k3]]'");
  LensDistortion distortion;
  bool ok = false;
  try {
    ok = camera_from_numbers(cam, distortion, parse_numbers(text, ' ', 10), path.string());
  } catch (const splat::Error& e) {
    fail(path, std::string(e.what()).substr(path.string().size() + 2));
  }
  if (!ok)
    fail(path, "expected 'fx fy cx cy', optionally followed by the distortion 'k1 k2 p1 p2 [k3]'");
  return distortion;
}

std::string intrinsics_text(const splat::Camera& camera, const LensDistortion& distortion) {
  std::string text;
  std::vector<double> values = {camera.fx, camera.fy, camera.cx, camera.cy};
  if (distortion.any()) {
    const std::vector<double> k = distortion.coefficients();
    values.insert(values.end(), k.begin(), k.end());
  }
  for (double v : values) {
    char number[40];
    std::snprintf(number, sizeof(number), "%s%.17g", text.empty() ? "" : ",", v);
    text += number;
  }
  return text;
}

void set_lens_distortion(Dataset& d, const LensDistortion& distortion, const std::string& where) {
  if (d.undistortion) d.intrinsics = d.undistortion->raw_camera();  // never undistorted twice
  d.distortion = distortion;
  d.undistortion.reset();
  if (!distortion.any()) return;
  d.undistortion = std::make_shared<const Undistortion>(d.intrinsics, distortion, where);
  d.intrinsics = d.undistortion->camera();
}

void set_camera(Dataset& d, const std::string& intrinsics, const std::filesystem::path& rgb) {
  const LensDistortion distortion = apply_intrinsics(d.intrinsics, intrinsics);
  set_size_from(d.intrinsics, rgb);
  set_lens_distortion(d, distortion, "intrinsics '" + intrinsics + "'");
}

void set_color_camera(Dataset& d, const ColorCameraChoice& choice) {
  d.color_registration.reset();
  d.color_estimate.reset();
  if (choice.kind == ColorCameraChoice::kRegistered) return;
  if (choice.kind == ColorCameraChoice::kGiven) {
    d.color_registration = std::make_shared<const ColorResampler>(d.intrinsics, choice.given);
    return;
  }
  // Frames spread over the sequence, as they load (undistorted).
  constexpr std::size_t kFrames = 8;
  std::vector<splat::RgbdFrame> frames;
  const std::size_t n = d.entries.size(), count = std::min(n, kFrames);
  for (std::size_t k = 0; k < count; ++k) frames.push_back(d.load(k * n / count));
  d.color_estimate = estimate_color_camera(frames);
  if (d.color_estimate->register_color) {
    d.color_registration = std::make_shared<const ColorResampler>(d.intrinsics, d.color_estimate->camera);
  }
}

Dataset open_dataset(const std::filesystem::path& root, const DatasetOptions& options) {
  const bool recording = is_bag_file(root);
  if (recording && !std::filesystem::is_regular_file(root)) fail(root, "recording does not exist");
  if (!recording && !std::filesystem::is_directory(root)) fail(root, "dataset folder does not exist");
  if (!recording && (!options.color_topic.empty() || !options.depth_topic.empty() || !options.gt_frames.empty())) {
    fail(root, "--color-topic, --depth-topic and --gt-frames are for ROS recordings (.bag, .mcap), not a folder");
  }
  Dataset d;
  if (recording) {
    d = open_bag(root, options);
    if (!options.intrinsics.empty()) {
      use_given_intrinsics(d, options.intrinsics);
    }
    if (options.gt_frames.empty()) attach_ground_truth(d, root.parent_path() / "groundtruth.txt");
  } else if (std::filesystem::exists(root / "rgb.txt") && std::filesystem::exists(root / "depth.txt")) {
    d = open_tum(root, options);
  } else if (std::filesystem::exists(root / "traj.txt") && std::filesystem::is_directory(root / "results")) {
    d = open_replica(root, options);
  } else if (ImageFolder images = list_image_folder(root);
             !std::filesystem::exists(root / "rgb.txt") && !std::filesystem::exists(root / "depth.txt") &&
             !images.colour.empty() && !images.depth.empty()) {
    d = open_images(root, images, options);
  } else {
    fail(root, "not a dataset folder (" + what_is_missing(root, images) +
                   "); accepted: TUM RGB-D (rgb.txt + depth.txt, lines 'timestamp path', "
                   "optional groundtruth.txt; camera from freiburg1/2/3 in the path or "
                   "--intrinsics), the plain folder (the same lists + intrinsics.txt 'fx fy cx "
                   "cy'), a folder of images (rgb/NAME.png|jpg + depth/NAME.png paired by name, "
                   "NAME the timestamp in seconds, + intrinsics.txt), Replica "
                   "(results/frameNNNNNN.jpg + results/depthNNNNNN.png + traj.txt), a ROS "
                   "recording (RUN.bag, RUN.mcap); see "
                   "docs/guide.md");
  }
  if (d.entries.empty()) {
    fail(root, "no frame has both colour and depth (" +
                   (d.listed == 0 ? std::string("none listed")
                                  : std::to_string(d.listed) + " listed: " + unused_frames(d)) +
                   ")");
  }
  if (options.max_frames > 0 && d.entries.size() > static_cast<std::size_t>(options.max_frames)) {
    d.beyond_max_frames = d.entries.size() - static_cast<std::size_t>(options.max_frames);
    d.entries.resize(static_cast<std::size_t>(options.max_frames));
  }
  if (!d.store) set_size_from(d.intrinsics, d.entries.front().rgb);
  set_lens_distortion(d, d.distortion, d.camera_source.empty() ? root.string() : d.camera_source);
  set_color_camera(d, parse_color_camera(options.color_camera));
  // Label images: named, or labels/ beside the colour folder.
  if (d.store && !options.labels.empty()) fail(options.labels, "label images are read for dataset folders, not recordings");
  if (!options.labels.empty()) {
    d.labels = read_label_set(options.labels);
  } else if (!d.store) {
    const std::filesystem::path beside = d.entries.front().rgb.parent_path().parent_path() / "labels";
    if (std::filesystem::exists(beside / "classes.json")) d.labels = read_label_set(beside);
  }
  return d;
}

std::optional<double> stem_number(const std::string& stem) {
  double value = 0;
  const char* end = stem.data() + stem.size();
  const auto [ptr, ec] = std::from_chars(stem.data(), end, value);
  if (ec != std::errc() || ptr != end || !std::isfinite(value)) return std::nullopt;
  return value;
}

}  // namespace app
