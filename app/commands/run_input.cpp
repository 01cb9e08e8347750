#include "commands/run_input.h"

#include <cstdio>
#include <fstream>

#include "io/slam_config_io.h"
#include "splat/error.h"

namespace app {

nlohmann::json run_input_json(const std::filesystem::path& input, const std::string& format, const splat::Camera& k,
                              double depth_scale, int max_frames, int test_every, const SlamConfig& config) {
  return {{"dataset", std::filesystem::absolute(input).string()},
          {"format", format},
          {"intrinsics", {{"fx", k.fx}, {"fy", k.fy}, {"cx", k.cx}, {"cy", k.cy}, {"width", k.width}, {"height", k.height}}},
          {"depth_scale", depth_scale},
          {"max_frames", max_frames},
          {"test_every", test_every},
          {"config", slam_config_to_json(config)}};
}

nlohmann::json lens_json(const Undistortion& undistortion) {
  const splat::Camera& raw = undistortion.raw_camera();
  const LensDistortion& d = undistortion.distortion();
  return {{"fx", raw.fx}, {"fy", raw.fy}, {"cx", raw.cx}, {"cy", raw.cy}, {"k1", d.k1},
          {"k2", d.k2},   {"p1", d.p1},   {"p2", d.p2},   {"k3", d.k3}};
}

RecordedInput recorded_input(const nlohmann::json& in, const std::string& where) {
  RecordedInput r;
  try {
    r.dataset = in.at("dataset").get<std::string>();
    // A distorting lens: the raw camera and its distortion, which undistort the frames again.
    const bool lens = in.contains("lens");
    const nlohmann::json& k = lens ? in.at("lens") : in.at("intrinsics");
    splat::Camera camera;
    camera.fx = k.at("fx").get<double>(), camera.fy = k.at("fy").get<double>();
    camera.cx = k.at("cx").get<double>(), camera.cy = k.at("cy").get<double>();
    LensDistortion distortion;
    if (lens) {
      distortion = {k.at("k1").get<double>(), k.at("k2").get<double>(), k.at("p1").get<double>(),
                    k.at("p2").get<double>(), k.at("k3").get<double>()};
    }
    r.options.intrinsics = intrinsics_text(camera, distortion);
    r.options.depth_scale = in.at("depth_scale").get<double>();
    r.options.max_frames = in.value("max_frames", 0);
    r.options.color_topic = in.value("color_topic", "");
    r.options.depth_topic = in.value("depth_topic", "");
    r.options.gt_frames = in.value("gt_frames", "");
    r.options.color_camera = in.value("color_camera", kRegisteredColor);  // runs before registration had none
    r.config = in.value("config", nlohmann::json());
    r.test_every = in.value("test_every", 0);
    if (r.test_every < 0) throw splat::Error(where + ": \"input\".test_every is negative");
  } catch (const nlohmann::json::exception& e) {
    throw splat::Error(where + ": \"input\" is malformed: " + e.what());
  }
  return r;
}

std::optional<Intrinsics> recorded_camera(const std::filesystem::path& summary_path) {
  std::ifstream in(summary_path);
  if (!in) throw splat::Error(summary_path.string() + ": cannot open file (not a run folder?)");
  const nlohmann::json summary = nlohmann::json::parse(in, nullptr, false);
  try {
    const nlohmann::json& k = summary.at("input").at("intrinsics");
    return Intrinsics{k.at("fx").get<double>(), k.at("fy").get<double>(), k.at("cx").get<double>(),
                      k.at("cy").get<double>(), k.at("width").get<int>(),  k.at("height").get<int>()};
  } catch (const nlohmann::json::exception&) {
    return std::nullopt;
  }
}

}  // namespace app
