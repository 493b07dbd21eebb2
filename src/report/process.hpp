// Running the external tools the report layer drives (gnuplot, ffmpeg) as
// child processes, without a shell: arguments are passed as they are, so paths
// with spaces or quotes need no escaping.
#pragma once

#include <string>
#include <sys/types.h>
#include <vector>

namespace comorph::report {

// Full path of `name` found on PATH, or "" when it is not installed.
std::string find_executable(const std::string& name);

// Throws a message naming the tool and the Debian package that provides it when
// `name` is not on PATH; returns its full path otherwise.
std::string require_executable(const std::string& name, const std::string& debian_package);

// Runs argv[0] (looked up on PATH) with stdout and stderr captured to a string;
// throws with the tool's own output when it exits non-zero.
std::string run_tool(const std::vector<std::string>& argv);

// A child process whose standard input we write to (ffmpeg reading raw frames).
// Uses a socket pair rather than a pipe so that a dead child gives an error
// (EPIPE) instead of killing us with SIGPIPE, without touching signal handlers.
class ChildInput {
 public:
  explicit ChildInput(const std::vector<std::string>& argv);
  ~ChildInput();  // closes the input and waits for the child
  ChildInput(const ChildInput&) = delete;
  ChildInput& operator=(const ChildInput&) = delete;

  // Writes all bytes; throws (with the child's stderr) if the child went away.
  void write(const void* data, size_t bytes);
  // Closes the child's input, waits for it; throws if it exited non-zero.
  void finish();

 private:
  std::string tool_;
  std::string log_path_;  // child's stderr, shown in error messages
  int fd_ = -1;
  pid_t pid_ = -1;
  std::string close_and_wait(int* status);
};

}  // namespace comorph::report
