#include "commands/progress.h"

#include <unistd.h>

#include <cmath>

namespace app {

Progress::Progress(std::string label, std::size_t total, std::string unit, std::FILE* out)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      total_(total),
      out_(out),
      tty_(::isatty(::fileno(out)) != 0),
      start_(std::chrono::steady_clock::now()),
      last_print_(start_) {}

double Progress::elapsed_seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void Progress::update(std::size_t done, const std::string& extra) {
  const auto now = std::chrono::steady_clock::now();
  const double since_print = std::chrono::duration<double>(now - last_print_).count();
  const bool open_ended = total_ == 0;  // a live stream: no total, no ETA
  const bool last = !open_ended && done >= total_;
  if (!tty_ && printed_ && !last && since_print < log_seconds_) return;
  if (tty_ && !last && since_print < 0.1) return;
  last_print_ = now;
  printed_ = true;
  const double elapsed = elapsed_seconds();
  const std::size_t done_here = done - std::min(done, resumed_at_);
  const double rate = elapsed > 0 ? static_cast<double>(done_here) / elapsed : 0;
  const double eta = rate > 0 ? static_cast<double>(total_ - std::min(done, total_)) / rate : 0;
  char count[64], eta_text[32] = "";
  if (open_ended) {
    std::snprintf(count, sizeof(count), "%zu", done);
  } else {
    std::snprintf(count, sizeof(count), "%zu/%zu", done, total_);
    std::snprintf(eta_text, sizeof(eta_text), ", ETA %.0f s", std::ceil(eta));
  }
  std::fprintf(out_, "%s%s %s, %.2f %s/s%s%s%s%s", tty_ ? "\r\033[K" : "", label_.c_str(), count, rate,
               unit_.c_str(), eta_text, extra.empty() ? "" : ", ", extra.c_str(), tty_ ? "" : "\n");
  std::fflush(out_);
}

void Progress::finish() {
  if (tty_ && printed_) std::fputc('\n', out_);
  std::fflush(out_);
}

}  // namespace app
