// One writer per run directory: an advisory lock (flock) on <dir>/.lock, held
// for as long as the RunLock lives. A second process that asks is refused at
// once with the holder's pid; the kernel drops the lock when its holder
// exits, however it exits, so a killed run never leaves a stale lock behind.
#pragma once

#include <string>

namespace comorph {

class RunLock {
 public:
  // Creates <dir>/.lock if needed and locks it; throws std::runtime_error
  // "<dir> is in use by process <pid> ..." when another process holds it.
  explicit RunLock(const std::string& dir);
  ~RunLock();
  RunLock(const RunLock&) = delete;
  RunLock& operator=(const RunLock&) = delete;

  static constexpr const char* kFileName = ".lock";

 private:
  int fd_ = -1;
};

}  // namespace comorph
