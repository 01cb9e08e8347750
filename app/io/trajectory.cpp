#include "io/trajectory.h"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "io/atomic_file.h"
#include "splat/error.h"

namespace app {

std::vector<StampedPose> read_tum_trajectory(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw splat::Error(path.string() + ": cannot open file");
  std::vector<StampedPose> poses;
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream words(line);
    double v[8];
    int count = 0;
    for (std::string word; count < 8 && words >> word; ++count) {
      char* end = nullptr;
      v[count] = std::strtod(word.c_str(), &end);
      if (end == word.c_str() || *end != '\0' || !std::isfinite(v[count])) {
        throw splat::Error(path.string() + ": line " + std::to_string(line_no) + ": '" + word + "' is not a finite number");
      }
    }
    if (std::string extra; count == 8 && words >> extra) {
      throw splat::Error(path.string() + ": line " + std::to_string(line_no) + " has more than 8 values ('" + extra +
                         "'), expected 8 (timestamp tx ty tz qx qy qz qw)");
    }
    if (count != 8) {
      throw splat::Error(path.string() + ": line " + std::to_string(line_no) + " has " + std::to_string(count) +
                         " values, expected 8 (timestamp tx ty tz qx qy qz qw)");
    }
    Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    const double norm = q.norm();
    if (norm < 0.9 || norm > 1.1) {
      throw splat::Error(path.string() + ": line " + std::to_string(line_no) + ": quaternion norm is " +
                         std::to_string(norm) + ", expected 1");
    }
    StampedPose pose;
    pose.timestamp = v[0];
    pose.T_world_cam.linear() = q.normalized().toRotationMatrix();
    pose.T_world_cam.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    poses.push_back(pose);
  }
  return poses;
}

void write_tum_trajectory(const std::filesystem::path& path, const std::vector<StampedPose>& poses) {
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    std::ofstream out(tmp);
    if (!out) throw splat::Error(tmp.string() + ": cannot open for writing");
    out << "# timestamp tx ty tz qx qy qz qw (camera to world), written by gslam\n";
    for (const auto& p : poses) {
      const Eigen::Quaterniond q(p.T_world_cam.linear());
      const Eigen::Vector3d t = p.T_world_cam.translation();
      out << std::fixed << std::setprecision(6) << p.timestamp << std::setprecision(9) << ' ' << t.x() << ' '
          << t.y() << ' ' << t.z() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << q.w() << '\n';
    }
    if (!out.flush()) throw splat::Error(tmp.string() + ": write failed");
  });
}

}  // namespace app
