#pragma once

namespace app {

// Parses the command line and runs the subcommand; returns the exit code. Errors from the
// libraries propagate as exceptions (main prints them as one line).
int run_cli(int argc, char** argv);

}  // namespace app
