#include "support/test_data.h"

namespace gslam::test {

std::filesystem::path shared_data_dir() { return GSLAM_SHARED_DATA_DIR; }

std::filesystem::path shared_data(const std::string& relative) {
  const std::filesystem::path path = shared_data_dir() / relative;
  return std::filesystem::exists(path) ? path : std::filesystem::path();
}

}  // namespace gslam::test
