#pragma once
#include <chrono>
#include <cstdio>
#include <string>

namespace app {

// Progress of a long job on stderr: "label i/N, rate unit/s, ETA" ("label i, rate unit/s" when
// the total is 0, unknown). Rewrites one line on a terminal; prints about every `log_seconds`
// otherwise (logs, CI).
class Progress {
 public:
  Progress(std::string label, std::size_t total, std::string unit, std::FILE* out = stderr);
  // A job resumed with `done` items already complete: rates and ETA count from there.
  void resume_at(std::size_t done) { resumed_at_ = done; }
  // Reports `done` items complete, with an optional suffix (for example "45,624 Gaussians").
  void update(std::size_t done, const std::string& extra = "");
  // Ends the progress line.
  void finish();
  double elapsed_seconds() const;

 private:
  std::string label_, unit_;
  std::size_t total_, resumed_at_ = 0;
  std::FILE* out_;
  bool tty_;
  std::chrono::steady_clock::time_point start_, last_print_;
  double log_seconds_ = 5.0;
  bool printed_ = false;
};

}  // namespace app
