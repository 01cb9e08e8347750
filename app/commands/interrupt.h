// Ctrl-C and SIGTERM for long commands: while an InterruptGuard lives, either signal only sets a
// flag, which the command polls to stop taking work and write complete outputs.
#pragma once
#include <csignal>

namespace app {

class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();  // restores the default handlers
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;
  // Whether a signal arrived since the guard was made.
  static bool interrupted();
};

}  // namespace app
