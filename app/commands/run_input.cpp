#include "commands/run_input.h"

#include <cstdio>

#include "io/slam_config_io.h"
#include "splat/error.h"

namespace app {

nlohmann::json run_input_json(const std::filesystem::path& input, const Dataset& dataset, int max_frames,
                              int test_every, const SlamConfig& config) {
  const splat::Camera& k = dataset.intrinsics;
  return {{"dataset", std::filesystem::absolute(input).string()},
          {"format", dataset.format},
          {"intrinsics", {{"fx", k.fx}, {"fy", k.fy}, {"cx", k.cx}, {"cy", k.cy}, {"width", k.width}, {"height", k.height}}},
          {"depth_scale", dataset.depth_scale},
          {"max_frames", max_frames},
          {"test_every", test_every},
          {"config", slam_config_to_json(config)}};
}

RecordedInput recorded_input(const nlohmann::json& in, const std::string& where) {
  RecordedInput r;
  try {
    r.dataset = in.at("dataset").get<std::string>();
    const nlohmann::json& k = in.at("intrinsics");
    char text[160];
    std::snprintf(text, sizeof(text), "%.17g,%.17g,%.17g,%.17g", k.at("fx").get<double>(), k.at("fy").get<double>(),
                  k.at("cx").get<double>(), k.at("cy").get<double>());
    r.options.intrinsics = text;
    r.options.depth_scale = in.at("depth_scale").get<double>();
    r.options.max_frames = in.value("max_frames", 0);
    r.config = in.value("config", nlohmann::json());
    r.test_every = in.value("test_every", 0);
    if (r.test_every < 0) throw splat::Error(where + ": \"input\".test_every is negative");
  } catch (const nlohmann::json::exception& e) {
    throw splat::Error(where + ": \"input\" is malformed: " + e.what());
  }
  return r;
}

}  // namespace app
