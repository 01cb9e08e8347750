#pragma once
#include <filesystem>

#include "datasets/dataset.h"
#include "datasets/synthetic_sequence.h"

namespace gslam::test {

// A generated sequence written to `dir` (TUM layout) and opened, as the tests read it.
inline app::Dataset synthetic_dataset(const std::filesystem::path& dir, const app::SyntheticOptions& options) {
  app::write_synthetic_sequence(dir, options);
  return app::open_dataset(dir);
}

}  // namespace gslam::test
