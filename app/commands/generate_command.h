#pragma once
#include <filesystem>
#include <string>

#include "datasets/synthetic_sequence.h"

namespace app {

struct GenerateOptions {
  std::filesystem::path out;
  bool suite = false;      // the hard-case suite (synthetic_suite.h), a folder per case
  bool overwrite = false;  // replace what an earlier generate wrote there (nothing else)
  SyntheticOptions sequence;  // one sequence (without `suite`)
  std::string distortion;     // "k1,k2,p1,p2[,k3]" for sequence.distortion; empty: none
};

// `gslam generate`: a synthetic RGB-D sequence with exact ground truth in TUM layout
// (synthetic_sequence.h), or the hard-case suite, ready for reconstruct and benchmark. Refuses a
// non-empty `out` unless `overwrite`. Throws splat::Error.
int run_generate(const GenerateOptions& options);

}  // namespace app
