// gslam command line: everything lives in the app library; this only turns errors into one line.
#include <cstdio>
#include <exception>

#include "commands/cli.h"

int main(int argc, char** argv) {
  try {
    return app::run_cli(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
