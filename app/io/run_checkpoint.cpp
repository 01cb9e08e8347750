#include "io/run_checkpoint.h"

#include <bit>
#include <cstring>
#include <fstream>

#include "io/atomic_file.h"
#include "io/file_error.h"
#include "tracking/moving_regions.h"

namespace app {
namespace {

static_assert(std::endian::native == std::endian::little, "checkpoints hold little-endian arrays");
constexpr char kMagic[] = "gslam checkpoint 2\n";
constexpr char kOlderMagic[] = "gslam checkpoint 1\n";  // before the map's free-space counts
using json = nlohmann::json;

json vector_to_json(const double* v, int n) { return json(std::vector<double>(v, v + n)); }

template <std::size_t N>
void vector_from_json(const json& j, double* out) {
  const auto v = j.get<std::vector<double>>();
  if (v.size() != N) throw splat::Error("expected " + std::to_string(N) + " numbers, got " + std::to_string(v.size()));
  std::copy(v.begin(), v.end(), out);
}

json poses_to_json(const std::vector<Eigen::Isometry3d>& poses) {
  json j = json::array();
  for (const auto& T : poses) j.push_back(pose_to_json(T));
  return j;
}

std::vector<Eigen::Isometry3d> poses_from_json(const json& j) {
  std::vector<Eigen::Isometry3d> poses;
  for (const json& p : j.get_ref<const json::array_t&>()) poses.push_back(pose_from_json(p));
  return poses;
}

// Moving-region labels (tracking::MovingLabel per pixel) as [label, run length] pairs: they are
// mostly static pixels.
json labels_to_json(const std::vector<uint8_t>& labels) {
  json runs = json::array();
  for (std::size_t i = 0; i < labels.size();) {
    std::size_t end = i;
    while (end < labels.size() && labels[end] == labels[i]) ++end;
    runs.push_back({labels[i], end - i});
    i = end;
  }
  return runs;
}

// All the moving labels a checkpoint may hold, in pixels: a crafted run length of a few bytes
// must not claim gigabytes. Tracking keeps a few sets at the moving regions' scale, which is at
// most a few hundred pixels wide (19,200 pixels a set at the default 160 px).
constexpr std::uint64_t kMaxLabelPixels = 16ull << 20;

// Throws splat::Error for a pair that is not a label and a length, or for more pixels than
// `pixels_left` (what the checkpoint's other sets left of kMaxLabelPixels).
std::vector<uint8_t> labels_from_json(const json& j, const std::string& what,
                                      std::uint64_t& pixels_left) {
  std::vector<uint8_t> labels;
  if (!j.is_array()) throw splat::Error(what + ": not a list of [label, length] runs");
  for (std::size_t r = 0; r < j.size(); ++r) {
    const json& run = j[r];
    auto where = [&] { return what + ": run " + std::to_string(r) + " " + run.dump().substr(0, 40); };
    if (!run.is_array() || run.size() != 2 || !run[0].is_number_unsigned() ||
        !run[1].is_number_unsigned() || run[0].get<std::uint64_t>() > tracking::kOutline) {
      throw splat::Error(where() + " is not a label (0-" + std::to_string(int(tracking::kOutline)) +
                         ") and a length");
    }
    const std::uint64_t length = run[1].get<std::uint64_t>();
    if (length > pixels_left) {
      throw splat::Error(where() + " reaches past the " + std::to_string(kMaxLabelPixels) +
                         " label pixels a checkpoint holds");
    }
    pixels_left -= length;
    labels.insert(labels.end(), static_cast<std::size_t>(length), run[0].get<uint8_t>());
  }
  return labels;
}

json label_sets_to_json(const std::vector<std::vector<uint8_t>>& sets) {
  json j = json::array();
  for (const auto& labels : sets) j.push_back(labels_to_json(labels));
  return j;
}

// Keyframes' moving labels, in the order of their list; `what` names the list.
std::vector<std::vector<uint8_t>> label_sets_from_json(const json& j, const std::string& what,
                                                       std::uint64_t& pixels_left) {
  if (!j.is_array()) throw splat::Error(what + "' moving labels are not a list");
  std::vector<std::vector<uint8_t>> sets;
  for (std::size_t k = 0; k < j.size(); ++k) {
    sets.push_back(
        labels_from_json(j[k], what + " " + std::to_string(k) + "'s moving labels", pixels_left));
  }
  return sets;
}

json tracker_to_json(const FrameTracker::State& t) {
  return {{"last_poses", poses_to_json(t.last_poses)},
          {"last_times", t.last_times},
          {"last_keyframe", pose_to_json(t.last_keyframe)},
          {"since_keyframe", t.since_keyframe},
          {"references", t.references},
          {"reference_rates", t.reference_rates},
          {"residual_spreads", t.residual_spreads},
          {"exposure_samples", t.exposure_samples},
          {"reference_labels", label_sets_to_json(t.reference_labels)},
          {"reference_twists", t.reference_twists},
          {"moving", labels_to_json(t.moving)}};
}

FrameTracker::State tracker_from_json(const json& j, std::uint64_t& label_pixels_left) {
  FrameTracker::State t{poses_from_json(j.at("last_poses")),
                        j.at("last_times").get<std::vector<double>>(),
                        pose_from_json(j.at("last_keyframe")),
                        j.at("since_keyframe").get<int>(),
                        j.at("references").get<std::vector<std::size_t>>(),
                        j.at("reference_rates").get<std::vector<double>>(),
                        j.at("residual_spreads").get<std::vector<double>>(),
                        j.at("exposure_samples").get<std::vector<std::array<double, 2>>>(),
                        {},
                        {},
                        {}};
  // Checkpoints written before the moving regions were kept have neither (nothing left out).
  if (j.contains("reference_labels"))
    t.reference_labels =
        label_sets_from_json(j.at("reference_labels"), "tracking's references", label_pixels_left);
  // Checkpoints from before the rolling shutter's correction have no velocities (zero).
  t.reference_twists = j.value("reference_twists", std::vector<std::array<double, 6>>{});
  if (j.contains("moving"))
    t.moving =
        labels_from_json(j.at("moving"), "the last frame's moving labels", label_pixels_left);
  return t;
}

json mapper_to_json(const mapping::MapperState& m) {
  json keyframes = json::array();
  for (const auto& kf : m.keyframes) {
    keyframes.push_back({{"number", kf.number}, {"T_cam_world", pose_to_json(kf.T_cam_world)},
                         {"adam_m", vector_to_json(kf.pose.m.data(), 6)}, {"adam_v", vector_to_json(kf.pose.v.data(), 6)},
                         {"adam_steps", kf.pose.steps}});
  }
  return {{"sh_degree", m.map.sh_degree}, {"keyframes", keyframes},
          {"vignetting", {m.vignetting.k1, m.vignetting.k2}}, {"vignetting_m", m.vignetting_m},
          {"vignetting_v", m.vignetting_v}, {"vignetting_steps", m.vignetting_steps},
          {"added", m.added}, {"rng", m.rng}};
}

mapping::MapperState mapper_from_json(const json& j) {
  mapping::MapperState m;
  m.map.sh_degree = m.adam.m.sh_degree = m.adam.v.sh_degree = j.at("sh_degree").get<int>();
  for (const json& kf : j.at("keyframes").get_ref<const json::array_t&>()) {
    mapping::MapperState::Keyframe k;
    k.number = kf.at("number").get<std::size_t>();
    k.T_cam_world = pose_from_json(kf.at("T_cam_world"));
    vector_from_json<6>(kf.at("adam_m"), k.pose.m.data());
    vector_from_json<6>(kf.at("adam_v"), k.pose.v.data());
    k.pose.steps = kf.at("adam_steps").get<int>();
    m.keyframes.push_back(k);
  }
  double vignetting[2];
  vector_from_json<2>(j.at("vignetting"), vignetting);
  m.vignetting = {vignetting[0], vignetting[1]};
  vector_from_json<2>(j.at("vignetting_m"), m.vignetting_m.data());
  vector_from_json<2>(j.at("vignetting_v"), m.vignetting_v.data());
  m.vignetting_steps = j.at("vignetting_steps").get<int>();
  m.added = j.at("added").get<std::size_t>();
  m.rng = j.at("rng").get<std::string>();
  return m;
}

json frames_to_json(const std::vector<SlamSystem::FramePose>& frames) {
  json j = json::array();
  for (const auto& f : frames) {
    j.push_back({{"keyframe", f.keyframe == SlamSystem::kNoKeyframe ? json(nullptr) : json(f.keyframe)},
                 {"T_keyframe_cam", pose_to_json(f.T_keyframe_cam)}, {"tracked", f.tracked},
                 {"is_keyframe", f.is_keyframe}, {"held_out", f.held_out}});
    if (f.T_colour_depth.matrix() != Eigen::Matrix4d::Identity()) {  // depth moved to the colour's instant
      j.back()["T_colour_depth"] = pose_to_json(f.T_colour_depth);
    }
    if (!f.moving.empty()) {  // what the final sweep leaves out of this frame
      j.back()["moving"] = {{"width", f.moving.width}, {"height", f.moving.height}, {"factor", f.moving.factor},
                            {"runs", f.moving.runs}};
    }
  }
  return j;
}

// A frame's moving mask as frames_to_json() wrote it; throws splat::Error naming the frame for
// sizes out of range or runs that do not cover the mask exactly.
MovingMask moving_mask_from_json(const json& j, std::size_t frame) {
  const std::string where = "frame " + std::to_string(frame) + "'s moving mask";
  MovingMask m;
  m.width = j.at("width").get<int>();
  m.height = j.at("height").get<int>();
  m.factor = j.at("factor").get<int>();
  if (m.width < 1 || m.width > 16384 || m.height < 1 || m.height > 16384 || m.factor < 1 || m.factor > 64) {
    throw splat::Error(where + ": size " + std::to_string(m.width) + "x" + std::to_string(m.height) + ", factor " +
                       std::to_string(m.factor) + " out of range");
  }
  const std::uint64_t pixels = std::uint64_t(m.width) * std::uint64_t(m.height);
  std::uint64_t covered = 0;
  const json& runs = j.at("runs");
  if (!runs.is_array() || runs.size() > pixels + 1) throw splat::Error(where + ": runs are not a list of run lengths");
  for (const json& run : runs) {
    if (!run.is_number_unsigned() || run.get<std::uint64_t>() > pixels) throw splat::Error(where + ": a run is not a length");
    m.runs.push_back(run.get<std::uint32_t>());
    covered += m.runs.back();
  }
  if (covered != pixels) {
    throw splat::Error(where + ": runs cover " + std::to_string(covered) + " pixels, the mask has " +
                       std::to_string(pixels));
  }
  return m;
}

std::vector<SlamSystem::FramePose> frames_from_json(const json& j) {
  std::vector<SlamSystem::FramePose> frames;
  for (const json& f : j.get_ref<const json::array_t&>()) {
    const json& keyframe = f.at("keyframe");
    frames.push_back({keyframe.is_null() ? SlamSystem::kNoKeyframe : keyframe.get<std::size_t>(),
                      pose_from_json(f.at("T_keyframe_cam")), f.at("tracked").get<bool>(),
                      f.at("is_keyframe").get<bool>(), f.at("held_out").get<bool>(),
                      f.contains("moving") ? moving_mask_from_json(f.at("moving"), frames.size()) : MovingMask{},
                      f.contains("T_colour_depth") ? pose_from_json(f.at("T_colour_depth")) : Eigen::Isometry3d::Identity()});
  }
  return frames;
}

json edges_to_json(const std::vector<tracking::PoseGraphEdge>& edges) {
  json j = json::array();
  for (const auto& e : edges) {
    j.push_back({{"i", e.i},
                 {"j", e.j},
                 {"T_i_j", pose_to_json(e.T_i_j)},
                 {"information", vector_to_json(e.information.data(), 36)},
                 {"loop", e.loop},
                 {"confirmed", e.confirmed}});
  }
  return j;
}

std::vector<tracking::PoseGraphEdge> edges_from_json(const json& j) {
  std::vector<tracking::PoseGraphEdge> edges;
  for (const json& e : j.get_ref<const json::array_t&>()) {
    tracking::PoseGraphEdge edge;
    edge.i = e.at("i").get<std::size_t>();
    edge.j = e.at("j").get<std::size_t>();
    edge.T_i_j = pose_from_json(e.at("T_i_j"));
    vector_from_json<36>(e.at("information"), edge.information.data());
    edge.loop = e.at("loop").get<bool>();
    edge.confirmed = e.value("confirmed", false);  // absent before confirmed loops
    edges.push_back(edge);
  }
  return edges;
}

json loop_events_to_json(const std::vector<LoopEvent>& events) {
  json j = json::array();
  for (const auto& e : events) {
    j.push_back({{"frame", e.frame}, {"matched_frame", e.matched_frame}, {"inliers", e.inliers},
                 {"drift_m", e.drift_m}, {"drift_deg", e.drift_deg}, {"accepted", e.accepted}});
    if (e.confirms_frame) j.back()["confirms_frame"] = *e.confirms_frame;
  }
  return j;
}

std::vector<LoopEvent> loop_events_from_json(const json& j) {
  std::vector<LoopEvent> events;
  for (const json& e : j.get_ref<const json::array_t&>()) {
    events.push_back({e.at("frame").get<std::size_t>(), e.at("matched_frame").get<std::size_t>(),
                      e.at("inliers").get<int>(), e.at("drift_m").get<double>(),
                      e.at("drift_deg").get<double>(), e.at("accepted").get<bool>(), std::nullopt});
    if (e.contains("confirms_frame"))
      events.back().confirms_frame = e.at("confirms_frame").get<std::size_t>();
  }
  return events;
}

json totals_to_json(const MappingTotals& t) {
  return {{"keyframes_mapped", t.keyframes_mapped}, {"keyframes_skipped", t.keyframes_skipped},
          {"keyframes_caught_up", t.keyframes_caught_up}, {"gaussians_added", t.gaussians_added},   {"gaussians_pruned", t.gaussians_pruned},
          {"ghosts_pruned", t.ghosts_pruned},
          {"covisible_edges", t.covisible_edges}, {"covisible_rejected", t.covisible_rejected},
          {"iterations", t.iterations},             {"last_loss", t.last_loss},
          {"mapping_ms", t.mapping_ms}};
}

MappingTotals totals_from_json(const json& j) {
  MappingTotals t;
  t.keyframes_mapped = j.at("keyframes_mapped").get<std::size_t>();
  t.keyframes_skipped = j.at("keyframes_skipped").get<std::size_t>();
  t.keyframes_caught_up = j.value("keyframes_caught_up", std::size_t{0});  // absent from older checkpoints
  t.gaussians_added = j.at("gaussians_added").get<std::size_t>();
  t.gaussians_pruned = j.at("gaussians_pruned").get<std::size_t>();
  t.ghosts_pruned = j.value("ghosts_pruned", std::size_t{0});  // absent from older checkpoints
  t.covisible_edges = j.value("covisible_edges", std::size_t{0});  // the same
  t.covisible_rejected = j.value("covisible_rejected", std::size_t{0});
  t.iterations = j.at("iterations").get<std::size_t>();
  t.last_loss = j.at("last_loss").get<double>();
  t.mapping_ms = j.at("mapping_ms").get<double>();
  return t;
}

// The map's and the optimizer's arrays, in one fixed order (State: const or not).
template <typename State, typename Visit>
void for_each_array(State& s, Visit visit) {
  for (splat::ParamGroup g : splat::kAllParamGroups) visit(splat::param_group(s.mapper.map, g));
  for (splat::ParamGroup g : splat::kAllParamGroups) visit(splat::param_group(s.mapper.adam.m, g));
  for (splat::ParamGroup g : splat::kAllParamGroups) visit(splat::param_group(s.mapper.adam.v, g));
  visit(s.mapper.adam.steps);
  visit(s.mapper.anchors);
  visit(s.mapper.seen_through);
  visit(s.mapper.seen_on);
}

// Reads exactly the bytes the file has, never more than remain.
class BoundedReader {
 public:
  explicit BoundedReader(const std::filesystem::path& path) : path_(path), in_(path, std::ios::binary) {
    if (!in_) fail(path, "cannot open checkpoint");
    std::error_code ec;
    remaining_ = std::filesystem::file_size(path, ec);
    if (ec) fail(path, "cannot read checkpoint size: " + ec.message());
  }
  void read(void* out, std::uint64_t bytes, const std::string& what) {
    if (bytes > remaining_) {
      fail(path_, "truncated checkpoint: " + what + " needs " + std::to_string(bytes) + " bytes, " +
                      std::to_string(remaining_) + " remain");
    }
    if (!in_.read(static_cast<char*>(out), static_cast<std::streamsize>(bytes))) fail(path_, "cannot read " + what);
    remaining_ -= bytes;
  }
  std::uint64_t remaining() const { return remaining_; }

 private:
  std::filesystem::path path_;
  std::ifstream in_;
  std::uint64_t remaining_ = 0;
};

// The keyframe overlapped mapping optimized and has not published (SlamSystem::State).
json unpublished_to_json(const SlamSystem::State::Unpublished& u) {
  return {{"keyframe", u.keyframe},           {"added", u.stats.added},
          {"pruned", u.stats.pruned},         {"ghosts", u.stats.ghosts},
          {"iterations", u.stats.iterations}, {"final_loss", u.stats.final_loss},
          {"window", u.stats.window},         {"optimize_ms", u.optimize_ms}};
}

SlamSystem::State::Unpublished unpublished_from_json(const json& j) {
  SlamSystem::State::Unpublished u;
  u.keyframe = j.at("keyframe").get<std::size_t>();
  u.stats.added = j.at("added").get<std::size_t>();
  u.stats.pruned = j.at("pruned").get<std::size_t>();
  u.stats.ghosts = j.at("ghosts").get<std::size_t>();
  u.stats.iterations = j.at("iterations").get<int>();
  u.stats.final_loss = j.at("final_loss").get<double>();
  u.stats.window = j.at("window").get<std::size_t>();
  u.optimize_ms = j.at("optimize_ms").get<double>();
  return u;
}

}  // namespace

json pose_to_json(const Eigen::Isometry3d& T) {
  json j = json::array();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) j.push_back(T.matrix()(r, c));
  return j;
}

Eigen::Isometry3d pose_from_json(const json& j) {
  const auto v = j.get<std::vector<double>>();
  if (v.size() != 12) throw splat::Error("a pose has 12 numbers (3x4, row by row), got " + std::to_string(v.size()));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) T.matrix()(r, c) = v[static_cast<std::size_t>(4 * r + c)];
  if (!T.matrix().allFinite()) throw splat::Error("a pose holds a non-finite number");
  return T;
}

void write_run_checkpoint(const std::filesystem::path& path, const RunCheckpoint& checkpoint) {
  const SlamSystem::State& s = checkpoint.slam;
  json header = {{"run", checkpoint.run},
                 {"tracker", tracker_to_json(s.tracker)},
                 {"mapper", mapper_to_json(s.mapper)},
                 {"mapper_keyframes", s.mapper_keyframes},
                 {"keyframe_world", poses_to_json(s.keyframe_world)},
                 {"frames", frames_to_json(s.frames)},
                 {"totals", totals_to_json(s.totals)},
                 {"edges", edges_to_json(s.back_end.edges)},
                 {"rejected_loops", edges_to_json(s.back_end.rejected_loops)},
                 {"loop_events", loop_events_to_json(s.loop_events)},
                 {"tracker_correction", pose_to_json(s.tracker_correction)},
                 {"covisible", s.back_end.covisible},
                 {"covisible_rates", s.back_end.covisible_rates},
                 {"covisible_labels", label_sets_to_json(s.back_end.covisible_labels)},
                 {"covisible_twists", s.back_end.covisible_twists}};
  if (s.unpublished) header["unpublished"] = unpublished_to_json(*s.unpublished);
  const std::string text = header.dump();
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    const std::uint64_t length = text.size();
    out.write(kMagic, sizeof(kMagic) - 1);
    out.write(reinterpret_cast<const char*>(&length), sizeof(length));
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    for_each_array(s, [&](const auto& values) {
      const std::uint64_t n = values.size();
      out.write(reinterpret_cast<const char*>(&n), sizeof(n));
      out.write(reinterpret_cast<const char*>(values.data()),
                static_cast<std::streamsize>(n * sizeof(values[0])));
    });
    if (!out.flush()) fail(tmp, "cannot write checkpoint");
  });
}

RunCheckpoint read_run_checkpoint(const std::filesystem::path& path) {
  BoundedReader in(path);
  char magic[sizeof(kMagic) - 1];
  in.read(magic, sizeof(magic), "header");
  if (std::memcmp(magic, kOlderMagic, sizeof(magic)) == 0) {
    fail(path, "checkpoint of an older gslam, which this one cannot continue; run again without --resume");
  }
  if (std::memcmp(magic, kMagic, sizeof(magic)) != 0) fail(path, "not a gslam checkpoint");
  std::uint64_t length = 0;
  in.read(&length, sizeof(length), "header length");
  if (length > in.remaining()) fail(path, "truncated checkpoint: header of " + std::to_string(length) + " bytes");
  std::string text(length, '\0');
  in.read(text.data(), length, "header");
  RunCheckpoint c;
  try {
    const json header = json::parse(text);
    c.run = header.at("run");
    std::uint64_t label_pixels_left = kMaxLabelPixels;
    c.slam.tracker = tracker_from_json(header.at("tracker"), label_pixels_left);
    c.slam.mapper = mapper_from_json(header.at("mapper"));
    c.slam.mapper_keyframes = header.at("mapper_keyframes").get<std::vector<std::size_t>>();
    c.slam.keyframe_world = poses_from_json(header.at("keyframe_world"));
    c.slam.frames = frames_from_json(header.at("frames"));
    c.slam.totals = totals_from_json(header.at("totals"));
    c.slam.back_end.edges = edges_from_json(header.at("edges"));
    if (header.contains("rejected_loops"))
      c.slam.back_end.rejected_loops = edges_from_json(header.at("rejected_loops"));
    c.slam.loop_events = loop_events_from_json(header.at("loop_events"));
    c.slam.tracker_correction = pose_from_json(header.at("tracker_correction"));
    // Checkpoints from before covisibility continue with none (it links the next keyframes).
    c.slam.back_end.covisible = header.value("covisible", std::vector<std::size_t>{});
    c.slam.back_end.covisible_rates = header.value("covisible_rates", std::vector<double>{});
    c.slam.back_end.covisible_twists = header.value("covisible_twists", std::vector<std::array<double, 6>>{});
    if (header.contains("covisible_labels")) {
      c.slam.back_end.covisible_labels = label_sets_from_json(
          header.at("covisible_labels"), "covisibility's keyframes", label_pixels_left);
    }
    if (header.contains("unpublished")) c.slam.unpublished = unpublished_from_json(header.at("unpublished"));
  } catch (const json::exception& e) {
    fail(path, std::string("malformed checkpoint header: ") + e.what());
  } catch (const splat::Error& e) {
    fail(path, std::string("malformed checkpoint header: ") + e.what());
  }
  int index = 0;
  for_each_array(c.slam, [&](auto& values) {
    const std::string what = "array " + std::to_string(index++);
    std::uint64_t n = 0;
    in.read(&n, sizeof(n), what + " length");
    if (n > in.remaining() / sizeof(values[0])) {
      fail(path, "truncated checkpoint: " + what + " claims " + std::to_string(n) + " values, " +
                     std::to_string(in.remaining()) + " bytes remain");
    }
    values.resize(n);
    in.read(values.data(), n * sizeof(values[0]), what);
  });
  if (in.remaining() != 0) fail(path, std::to_string(in.remaining()) + " bytes after the checkpoint's last array");
  return c;
}

}  // namespace app
