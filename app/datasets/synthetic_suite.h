// The generated hard cases every default is checked on besides the real sequences
// (docs/tuning.md): `gslam generate OUT --suite` writes them, `gslam benchmark OUT` runs them.
#pragma once
#include <string>
#include <vector>

#include "datasets/synthetic_sequence.h"

namespace app {

struct SyntheticCase {
  std::string name;  // its folder under the suite's
  std::string what;  // one line for the listing
  SyntheticOptions options;
};

// Fast rotation, motion blur, depth holes and noise, loops, a miscalibrated camera and one long
// sequence (the final sweep's share of a run grows with its length).
std::vector<SyntheticCase> hard_case_suite();

}  // namespace app
