// `comorph experiment --jobs/--slurm` under the engines that run them: a real
// one-node Slurm cluster (scripts/slurm-local.sh: munged, slurmctld, slurmd)
// runs the array of a ci-size Table I with two seeds, one task killed halfway
// before and resumed by the array; GNU parallel runs the same job list and
// gives the same table. Faults: two jobs on one run directory (one is
// refused by the run lock), a config error (every job fails with the same one
// line before any training).
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "common/file_io.hpp"
#include "support/test_support.hpp"

namespace {
namespace fs = std::filesystem;
using comorph::test_support::read_text;
using Clock = std::chrono::steady_clock;

const std::string kSource = COMORPH_SOURCE_DIR;
const std::string kCi = kSource + "/configs/ci.yaml";
// Each run a few seconds: ci.yaml's 6 episodes on one core (no learner
// thread, one evaluation worker), no periodic evaluation, 2 evaluation episodes.
const std::string kSeconds =
    " --set trainer.learner_thread=false --set eval.workers=1 --set trainer.eval_interval=0 --eval-episodes 2";
// Table I's columns.
const std::vector<std::string> kColumns = {"hier-td3", "fixed-2", "fixed-4", "fixed-6", "fixed-8", "fixed-10"};

int run_cli(const std::string& args, std::string& output) { return comorph::test_support::run_comorph(args, output); }

// `command` through the shell, stdout and stderr in `output`; its exit code.
int run_shell(const std::string& command, std::string& output) {
  const fs::path log = fs::temp_directory_path() / ("comorph_engines_" + std::to_string(::getpid()) + ".log");
  const int status = std::system((command + " > " + log.string() + " 2>&1").c_str());
  output = read_text(log);
  fs::remove(log);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// A job line as the engine runs it (its output goes to its run directory's
// job log); its exit code.
int run_job(const std::string& line) {
  const int status = std::system(line.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

bool have_tool(const std::string& name) {
  std::string out;
  return run_shell("command -v " + name, out) == 0;
}

// A tool the test needs: CI (root, scripts/install-deps.sh) has it, so there
// its absence fails; elsewhere the test is skipped saying why.
#define NEED_TOOL(name, package)                                                                            \
  if (!have_tool(name)) {                                                                                   \
    if (::getuid() == 0) FAIL() << name << " is missing: scripts/install-deps.sh installs " << package;     \
    GTEST_SKIP() << name << " is missing (Debian package " << package << ", scripts/install-deps.sh)"; \
  }

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) lines.push_back(line);
  return lines;
}

// A job line started in its own process group, so that the whole job (shell
// and comorph) can be killed at once.
pid_t start_job(const std::string& line) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::setsid();
    ::execl("/bin/sh", "sh", "-c", line.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

// Waits until `path` exists; false after `seconds`.
bool wait_for(const fs::path& path, double seconds) {
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  while (!fs::exists(path)) {
    if (Clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

// The one-node cluster of scripts/slurm-local.sh, stopped however the test ends.
struct LocalSlurm {
  std::string dir;
  std::string start_log;
  bool started = false;
  explicit LocalSlurm(const std::string& d) : dir(d) {
    started = run_shell("bash " + kSource + "/scripts/slurm-local.sh start " + dir, start_log) == 0;
    ::setenv("SLURM_CONF", (dir + "/slurm.conf").c_str(), 1);
  }
  // Before `dir` is removed: its pid files name the daemons.
  void stop() {
    std::string log;
    if (!dir.empty()) run_shell("bash " + kSource + "/scripts/slurm-local.sh stop " + dir, log);
    dir.clear();
    ::unsetenv("SLURM_CONF");
  }
  ~LocalSlurm() { stop(); }
};

TEST(ExperimentEngines, SlurmArrayAndGnuParallelGiveTheSameTable) {
  if (::getuid() != 0) GTEST_SKIP() << "not root: cannot start munged, slurmctld and slurmd (CI runs as root)";
  NEED_TOOL("slurmctld", "slurm-wlm");
  NEED_TOOL("munged", "munge");
  NEED_TOOL("parallel", "parallel");
  const std::string root = comorph::test_support::fresh_temp_dir("engines");
  const std::string common = "experiment --table 1 --config " + kCi + kSeconds + " --seeds 1-2";
  const std::string on_slurm = root + "/slurm", on_parallel = root + "/parallel";
  std::string log;
  ASSERT_EQ(run_cli(common + " --out " + on_slurm + " --slurm " + root + "/table1.sbatch --jobs " + root +
                        "/slurm-jobs.txt",
                    log),
            0)
      << log;
  EXPECT_NE(log.find("12 array tasks, 1 core each"), std::string::npos) << log;
  ASSERT_EQ(run_cli(common + " --out " + on_parallel + " --jobs " + root + "/jobs.txt", log), 0) << log;
  const auto slurm_jobs = lines_of(read_text(root + "/slurm-jobs.txt"));
  ASSERT_EQ(slurm_jobs.size(), 12u);
  EXPECT_EQ(lines_of(read_text(root + "/jobs.txt")).size(), 12u);

  // Task 0 (hier-td3, seed 1) killed halfway: after its first checkpoint, before its end.
  const fs::path killed = on_slurm + "/hier-td3-seed-1";
  const pid_t job = start_job(slurm_jobs[0]);
  const bool checkpointed = wait_for(killed / "checkpoint", 120);
  ::kill(-job, SIGKILL);
  ::waitpid(job, nullptr, 0);
  ASSERT_TRUE(checkpointed) << read_text(killed / "job.log");
  ASSERT_FALSE(fs::exists(killed / "finished")) << "task 0 ended before it was killed";

  LocalSlurm slurm(root + "/cluster");
  ASSERT_TRUE(slurm.started) << slurm.start_log;
  const auto start = Clock::now();
  // Bounded: a cluster that never runs the tasks fails the test instead of hanging it.
  ASSERT_EQ(run_shell("timeout 600 sbatch --wait --array=0-11%2 " + root + "/table1.sbatch", log), 0) << log;
  const double slurm_s = std::chrono::duration<double>(Clock::now() - start).count();
  std::printf("Slurm: 12 tasks, at most 2 at once: %.0f s\n", slurm_s);
  for (const auto& column : kColumns)
    for (int seed : {1, 2}) {
      const fs::path run = on_slurm + "/" + column + "-seed-" + std::to_string(seed);
      EXPECT_TRUE(fs::exists(run / "finished")) << run << "\n" << read_text(run / "job.log");
      EXPECT_NE(read_text(run / "config.yaml").find("  seed: " + std::to_string(seed) + "\n"), std::string::npos);
    }
  EXPECT_NE(read_text(killed / "job.log").find("resuming " + killed.string() + " after"), std::string::npos)
      << read_text(killed / "job.log");

  // The table: every cell has its two seeds, nothing is missing.
  ASSERT_EQ(run_cli("experiment --table 1 --seeds 1-2 --out " + on_slurm + " --collect", log), 0) << log;
  const std::string table = read_text(on_slurm + "/table-1.md");
  for (const char* column : {"Ours (hierarchical) [2 runs]", "Fixed 2 [2 runs]", "Fixed 10 [2 runs]"})
    EXPECT_NE(table.find(column), std::string::npos) << column << " not in\n" << table;
  std::size_t two_seeds = 0;
  for (std::size_t at = table.find("| 1, 2 / n/a"); at != std::string::npos; at = table.find("| 1, 2 / n/a", at + 1))
    ++two_seeds;
  EXPECT_EQ(two_seeds, kColumns.size()) << table;
  for (const char* absent : {"(1 seed) /", "— /", "Missing"}) EXPECT_EQ(table.find(absent), std::string::npos) << table;
  EXPECT_NE(read_text(on_slurm + "/report/report.md").find("Fixed 2 [2 runs]"), std::string::npos);

  // A finished run is never trained again.
  const std::string episodes = read_text(killed / "episodes.csv");
  ASSERT_EQ(run_job(slurm_jobs[0]), 0) << read_text(killed / "job.log");
  EXPECT_NE(read_text(killed / "job.log").find("done before"), std::string::npos);
  EXPECT_EQ(read_text(killed / "episodes.csv"), episodes);

  // GNU parallel on the job list of another directory: the same table.
  const auto parallel_start = Clock::now();
  ASSERT_EQ(run_shell("parallel -j 2 < " + root + "/jobs.txt", log), 0) << log;
  std::printf("GNU parallel: 12 jobs, 2 at once: %.0f s\n",
              std::chrono::duration<double>(Clock::now() - parallel_start).count());
  ASSERT_EQ(run_cli("experiment --table 1 --seeds 1-2 --out " + on_parallel + " --collect", log), 0) << log;
  EXPECT_EQ(read_text(on_parallel + "/table-1.md"), table);
  slurm.stop();
  fs::remove_all(root);
}

TEST(ExperimentEngines, TwoJobsOnOneRunDirectoryOneIsRefused) {
  const std::string root = comorph::test_support::fresh_temp_dir("engines_lock");
  std::string log;
  // Long enough to be running when the second job starts.
  ASSERT_EQ(run_cli("experiment --table 1 --only fixed-2 --seeds 3 --config " + kCi + kSeconds +
                        " --set trainer.episodes=400 --out " + root + "/out --jobs " + root + "/jobs.txt",
                    log),
            0)
      << log;
  const auto jobs = lines_of(read_text(root + "/jobs.txt"));
  ASSERT_EQ(jobs.size(), 1u);
  const fs::path run = root + "/out/fixed-2-seed-3";
  const pid_t first = start_job(jobs[0]);
  const bool running = wait_for(run / "config.yaml", 120);
  const int second = run_job(jobs[0]);
  ::kill(-first, SIGKILL);
  ::waitpid(first, nullptr, 0);
  ASSERT_TRUE(running) << read_text(run / "job.log");
  EXPECT_EQ(second, 1);
  const std::string job_log = read_text(run / "job.log");
  EXPECT_NE(job_log.find(run.string() + " is in use by process "), std::string::npos) << job_log;
  fs::remove_all(root);
}

TEST(ExperimentEngines, ConfigErrorFailsEveryJobWithTheSameLineBeforeTraining) {
  NEED_TOOL("parallel", "parallel");
  const std::string root = comorph::test_support::fresh_temp_dir("engines_config");
  const std::string config = root + "/ci.yaml";
  fs::copy_file(kCi, config);
  std::string log;
  ASSERT_EQ(run_cli("experiment --table 1 --seeds 1-2 --config " + config + kSeconds + " --out " + root +
                        "/out --jobs " + root + "/jobs.txt",
                    log),
            0)
      << log;
  // Broken after the job list was written: every job meets it.
  std::string text = read_text(config);
  text.replace(text.find("  episodes: 4\n"), 14, "  episodes: -4\n");
  comorph::write_file_atomic(config, text);
  EXPECT_EQ(run_shell("parallel -j 2 < " + root + "/jobs.txt", log), 12) << log;  // parallel: failed jobs
  std::vector<std::string> messages;
  for (const auto& entry : fs::directory_iterator(root + "/out")) {
    EXPECT_FALSE(fs::exists(entry.path() / "config.yaml")) << entry.path() << " started training";
    messages.push_back(read_text(entry.path() / "job.log"));
  }
  ASSERT_EQ(messages.size(), 12u);
  EXPECT_EQ(std::count(messages[0].begin(), messages[0].end(), '\n'), 1) << messages[0];
  EXPECT_NE(messages[0].find("comorph: error: " + config), std::string::npos) << messages[0];
  EXPECT_NE(messages[0].find("trainer.episodes"), std::string::npos) << messages[0];
  for (const auto& m : messages) EXPECT_EQ(m, messages[0]);
  fs::remove_all(root);
}

}  // namespace
