// Running programs as child processes: with their output in a log file (gslam benchmark runs
// each sequence's reconstruct and eval so, each with its own memory and failure), several at
// once (--jobs), with their output captured (sbatch, squeue), or fed through their standard
// input (ffmpeg encoding a video).
#pragma once
#include <sys/types.h>

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace app {

// The running gslam executable (/proc/self/exe).
std::filesystem::path this_executable();

// Starts `args` (args[0] the program, found on PATH if it has no '/') with standard input closed
// and standard output and error appended to `log`, in this process's environment with
// `environment`'s NAME=value entries before it (so they win); does not wait. Throws
// splat::Error if it cannot be started.
pid_t start_logged(const std::vector<std::string>& args, const std::filesystem::path& log,
                   const std::vector<std::string>& environment = {});

// A child whose standard input this process writes through `input`: a socket rather than a
// pipe, so that writing to a child that has ended is an error (send's EPIPE), never a SIGPIPE
// that would end this process.
struct PipedChild {
  pid_t pid = 0;
  int input = -1;
};
// Starts `args` as start_logged does, with standard input read from the returned socket.
PipedChild start_piped(const std::vector<std::string>& args, const std::filesystem::path& log);
// Writes all of `bytes` to a child's input; false if the child no longer reads it.
bool write_to_child(const PipedChild& child, std::span<const std::uint8_t> bytes);

// Waits for a child started above. Returns its exit code, or 128 + the signal that ended it.
int wait_for_child(pid_t pid);

struct EndedChild {
  pid_t pid = 0;
  int exit_code = 0;  // as wait_for_child
};
// Waits for whichever child of this process ends first. Throws splat::Error if there is none.
EndedChild wait_for_any_child();

// start_logged, then wait_for_child.
int run_logged(const std::vector<std::string>& args, const std::filesystem::path& log);

struct CapturedRun {
  int exit_code = 0;   // as wait_for_child
  std::string output;  // standard output and error together
};
// Runs `args` as run_logged does, its output captured instead of logged.
CapturedRun run_captured(const std::vector<std::string>& args);

// Whether `program` is a file on PATH that can be run.
bool program_on_path(const std::string& program);

// The last non-empty line of a text file (a failed child's error), "" if none.
std::string last_line(const std::filesystem::path& file);

}  // namespace app
