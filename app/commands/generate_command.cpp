#include "commands/generate_command.h"

#include <cstdio>

#include "datasets/synthetic_suite.h"
#include "splat/error.h"

namespace app {
namespace {

// With `overwrite`, what an earlier generate wrote into `dir` goes first (so that no frame of a
// longer sequence stays behind); whatever else the folder holds stays.
void write_one(const std::filesystem::path& dir, const SyntheticOptions& options, bool overwrite) {
  if (overwrite) {
    for (const char* entry : {"rgb", "depth", "labels", "rgb.txt", "depth.txt", "intrinsics.txt", "groundtruth.txt"}) {
      std::filesystem::remove_all(dir / entry);
    }
  }
  write_synthetic_sequence(dir, options);
}

}  // namespace

int run_generate(const GenerateOptions& o) {
  std::error_code ec;
  if (std::filesystem::exists(o.out) && !std::filesystem::is_directory(o.out)) {
    throw splat::Error(o.out.string() + ": exists and is not a folder");
  }
  if (!o.overwrite && std::filesystem::is_directory(o.out) && !std::filesystem::is_empty(o.out, ec)) {
    throw splat::Error(o.out.string() + ": not empty; give --overwrite to replace what is there");
  }
  if (!o.suite) {
    SyntheticOptions sequence = o.sequence;
    if (!o.distortion.empty()) sequence.distortion = parse_lens_distortion(o.distortion);
    write_one(o.out, sequence, o.overwrite);
    std::printf("generated %d frames (%dx%d) -> %s\n", o.sequence.frames, o.sequence.width, o.sequence.height,
                o.out.c_str());
    return 0;
  }
  const std::vector<SyntheticCase> suite = hard_case_suite();
  for (std::size_t i = 0; i < suite.size(); ++i) {
    const SyntheticCase& c = suite[i];
    std::fprintf(stderr, "generate %zu/%zu: %s (%s)\n", i + 1, suite.size(), c.name.c_str(), c.what.c_str());
    write_one(o.out / c.name, c.options, o.overwrite);
  }
  std::printf("generated %zu sequences -> %s (run them with: gslam benchmark %s --out RESULTS)\n", suite.size(),
              o.out.c_str(), o.out.c_str());
  return 0;
}

}  // namespace app
