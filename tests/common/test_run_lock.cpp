// The run lock between two processes: a second writer is refused at once with
// the holder's pid, and a holder killed with SIGKILL leaves nothing that blocks.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <string>

#include "common/run_lock.hpp"
#include "support/test_support.hpp"

namespace comorph {
namespace {

// Forks a child that takes the lock on `dir`, reports on a pipe and then waits
// to be killed. Returns its pid once it holds the lock.
pid_t child_holding_lock(const std::string& dir) {
  int ready[2];
  if (pipe(ready) != 0) return -1;
  const pid_t pid = fork();
  if (pid == 0) {
    close(ready[0]);
    try {
      RunLock lock(dir);
      const char ok = 1;
      if (write(ready[1], &ok, 1) != 1) _exit(2);
      while (true) pause();
    } catch (...) {
      _exit(3);
    }
  }
  close(ready[1]);
  char ok = 0;
  const bool got = read(ready[0], &ok, 1) == 1;
  close(ready[0]);
  return got ? pid : -1;
}

std::string lock_error(const std::string& dir) {
  try {
    RunLock lock(dir);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(RunLock, ASecondProcessIsRefusedWithTheHoldersPidAndAKilledHolderDoesNotBlock) {
  const std::string dir = test_support::fresh_temp_dir("run_lock");
  const pid_t holder = child_holding_lock(dir);
  ASSERT_GT(holder, 0);
  const std::string e = lock_error(dir);
  EXPECT_NE(e.find(dir + " is in use by process " + std::to_string(holder)), std::string::npos) << e;
  kill(holder, SIGKILL);
  int status = 0;
  waitpid(holder, &status, 0);
  // The .lock file is still there with the dead pid in it; flock is not.
  EXPECT_EQ(lock_error(dir), "");
}

TEST(RunLock, IsReleasedWhenTheHolderGoesOutOfScope) {
  const std::string dir = test_support::fresh_temp_dir("run_lock_scope");
  {
    RunLock first(dir);
    EXPECT_NE(lock_error(dir).find("is in use by process " + std::to_string(getpid())), std::string::npos);
  }
  EXPECT_EQ(lock_error(dir), "");
}

TEST(RunLock, AMissingDirectoryIsAnError) {
  EXPECT_NE(lock_error("/nonexistent-run-dir").find("cannot open the lock file /nonexistent-run-dir/.lock"),
            std::string::npos);
}

}  // namespace
}  // namespace comorph
