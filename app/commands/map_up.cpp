#include "commands/map_up.h"

#include <fstream>

#include <nlohmann/json.hpp>

#include "splat/error.h"
#include "viewer/views.h"

namespace app {

MapUp choose_map_up(const std::optional<Eigen::Vector3d>& given, const std::filesystem::path& map_file,
                    const std::vector<Eigen::Isometry3d>& poses, const splat::Gaussians& map) {
  if (given) {
    if (!given->allFinite() || given->norm() == 0) throw splat::Error("--up: expected a non-zero finite vector x,y,z");
    return {given->normalized(), "--up"};
  }
  std::ifstream in(map_file.parent_path() / "summary.json");
  const nlohmann::json summary = in ? nlohmann::json::parse(in, nullptr, false) : nlohmann::json();
  if (summary.is_object() && summary.contains("world_up")) {
    const nlohmann::json& u = summary["world_up"];
    try {
      const Eigen::Vector3d up(u.at("x").get<double>(), u.at("y").get<double>(), u.at("z").get<double>());
      if (up.allFinite() && up.norm() > 0) return {up.normalized(), "from summary.json world_up"};
    } catch (const nlohmann::json::exception&) {  // malformed: estimated below, as for an older run
    }
  }
  if (!poses.empty()) {
    const WorldUp up = estimate_world_up(poses, map);
    return {up.up, std::string("estimated from the camera poses: ") + up.source_name()};
  }
  return {Eigen::Vector3d::UnitZ(), "default; --up x,y,z sets it"};
}

}  // namespace app
