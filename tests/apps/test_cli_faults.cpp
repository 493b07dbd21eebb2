// The command line under faults (docs/faults.md), as a user meets them: a full disk
// (/dev/full, a file-size limit), a second writer of a run directory, a run
// directory whose CSV files do not fit its checkpoint, bad numbers on the
// command line, missing config directories, directories given as files and
// oversized inputs. Every case must end non-zero with a message naming the
// cause.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "common/run_lock.hpp"
#include "support/test_support.hpp"

namespace {
namespace fs = std::filesystem;

const std::string kCi = std::string(COMORPH_SOURCE_DIR) + "/configs/ci.yaml";
const std::string kSim = std::string(COMORPH_SOURCE_DIR) + "/configs/sim";

using comorph::test_support::read_text;
int run_cli(const std::string& args, std::string& output) { return comorph::test_support::run_comorph(args, output); }
// std::system's status -> the exit code.
int exit_code(int status) { return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status); }
// Runs a shell command line; stderr (and stdout, unless the command sends it
// elsewhere first) in `output`.
int run_shell(const std::string& command, std::string& output) {
  const std::string log = comorph::test_support::fresh_temp_dir("cli_shell") + "/log";
  const int status = std::system(("{ " + command + "; } > " + log + " 2>&1").c_str());
  output = read_text(log);
  return status;
}
const std::string kExe = COMORPH_EXE;

// The shortest training run: the ci preset's 2 warm-up episodes, one checkpoint.
const std::string kTinyRun = "--config " + kCi + " --set trainer.episodes=0 --set trainer.eval_interval=0";

std::string temp_dir(const std::string& name) { return comorph::test_support::fresh_temp_dir("cli_" + name); }

// A trained tiny run, shared by the tests of this process (trained once).
const std::string& tiny_run() {
  static const std::string dir = [] {
    const std::string d = temp_dir("tiny") + "/run";
    std::string log;
    EXPECT_EQ(run_cli("train " + kTinyRun + " --out " + d, log), 0) << log;
    return d;
  }();
  return dir;
}

// A copy of the tiny run to damage.
std::string copy_of_tiny_run(const std::string& name) {
  const std::string d = temp_dir(name) + "/run";
  fs::copy(tiny_run(), d, fs::copy_options::recursive);
  return d;
}

TEST(FullDisk, StdoutCommandsFailOnDevFull) {
  std::string log;
  EXPECT_EQ(exit_code(run_shell(kExe + " config chain -n 3 2>&1 > /dev/full", log)), 1);
  EXPECT_NE(log.find("cannot write standard output: No space left on device"), std::string::npos) << log;
  EXPECT_EQ(exit_code(run_shell(kExe + " export-mjcf --modules 4 --seed 3 --config-dir " + kSim + " 2>&1 > /dev/full",
                                log)),
            1);
  EXPECT_NE(log.find("cannot write standard output: No space left on device"), std::string::npos) << log;
}

TEST(FullDisk, SummarizeAndEvalNameTheFileAndWriteNoWroteLine) {
  std::string log;
  const std::string run = copy_of_tiny_run("full_eval");
  EXPECT_EQ(exit_code(run_cli("summarize " + run + "/episodes.csv --out /dev/full", log)), 1);
  EXPECT_NE(log.find("cannot write /dev/full: No space left on device"), std::string::npos) << log;
  // The evaluation JSON on a full disk (a link to /dev/full stands for it).
  fs::create_symlink("/dev/full", run + "/eval-default.json");
  EXPECT_EQ(exit_code(run_cli("eval --run " + run + " --episodes 1 --workers 1", log)), 1);
  EXPECT_NE(log.find("cannot write " + run + "/eval-default.json: No space left on device"), std::string::npos)
      << log;
  EXPECT_EQ(log.find("wrote"), std::string::npos) << log;
}

// A file-size limit fails the checkpoint's writes as a full disk would: the
// training stops with the file and the reason, exit 1 (not torch's abort, 134).
TEST(FullDisk, TrainingStopsWithTheMessage) {
  const std::string run = temp_dir("full_train") + "/run";
  std::string log;
  const int code = exit_code(run_shell("ulimit -f 32; " + kExe + " train " + kTinyRun + " --out " + run, log));
  EXPECT_EQ(code, 1) << log;
  EXPECT_NE(log.find("cannot write " + run + "/"), std::string::npos) << log;
  EXPECT_NE(log.find("File too large"), std::string::npos) << log;
}

TEST(RunLock, ASecondWriterIsRefusedWithTheHoldersPid) {
  const std::string run = copy_of_tiny_run("lock");
  const std::string pid = std::to_string(::getpid());
  std::string log;
  {
    comorph::RunLock held(run);  // this test process is the other writer
    EXPECT_EQ(exit_code(run_cli("train --resume " + run, log)), 1);
    EXPECT_NE(log.find(run + " is in use by process " + pid), std::string::npos) << log;
    const std::string fresh = temp_dir("lock_new") + "/run";
    fs::create_directories(fresh);
    comorph::RunLock held_fresh(fresh);
    EXPECT_EQ(exit_code(run_cli("train " + kTinyRun + " --out " + fresh, log)), 1);
    EXPECT_NE(log.find(fresh + " is in use by process " + pid), std::string::npos) << log;
  }
  // An experiment column is locked for its training and evaluations too.
  const std::string experiment = temp_dir("lock_experiment");
  fs::create_directories(experiment + "/hier-td3");
  {
    comorph::RunLock held(experiment + "/hier-td3");
    EXPECT_EQ(exit_code(run_cli("experiment --table 2 --only hier-td3 --config " + kCi + " --out " + experiment, log)),
              1);
    EXPECT_NE(log.find(experiment + "/hier-td3 is in use by process " + pid), std::string::npos) << log;
  }
  // Released (as when the holder is killed): the resume runs (nothing left to train).
  EXPECT_EQ(exit_code(run_cli("train --resume " + run, log)), 0) << log;
}

TEST(Resume, EpisodesCsvShorterThanTheCheckpointOrDamagedIsRefused) {
  std::string log;
  const std::string shorter = copy_of_tiny_run("short_csv");
  std::string csv = read_text(shorter + "/episodes.csv");
  csv = csv.substr(0, csv.rfind('\n', csv.size() - 2) + 1);  // drop the last row
  std::ofstream(shorter + "/episodes.csv", std::ios::trunc) << csv;
  EXPECT_EQ(exit_code(run_cli("train --resume " + shorter, log)), 1);
  EXPECT_NE(log.find("episodes.csv: 1 rows, but the checkpoint"), std::string::npos) << log;
  EXPECT_NE(log.find("counts 2 episodes; refusing to resume with a gap"), std::string::npos) << log;

  const std::string garbage = copy_of_tiny_run("garbage_csv");
  std::string rows = read_text(garbage + "/episodes.csv");
  rows.replace(rows.find('\n') + 1, 5, "xx,yy");  // the first data row
  std::ofstream(garbage + "/episodes.csv", std::ios::trunc) << rows;
  EXPECT_EQ(exit_code(run_cli("train --resume " + garbage, log)), 1);
  EXPECT_NE(log.find("episodes.csv:2:"), std::string::npos) << log;
  EXPECT_NE(log.find("refusing to resume from a damaged episodes.csv"), std::string::npos) << log;
}

TEST(Numbers, BadNumbersOnTheCommandLineAreErrorsNamingTheOption) {
  std::string log;
  // Checked while the command line is parsed: no run is needed to see it.
  const std::string run = "/nonexistent/run";
  for (const std::string bad : {"--episodes -3", "--workers -1", "--seed -5", "--episodes nan"}) {
    EXPECT_EQ(exit_code(run_cli("eval --run " + run + " " + bad, log)), 2) << bad;  // a command-line error
    EXPECT_NE(log.find(bad.substr(0, bad.find(' '))), std::string::npos) << bad << ": " << log;
    EXPECT_NE(log.find("expected a whole number"), std::string::npos) << bad << ": " << log;
  }
  const std::string mjcf = "export-mjcf --config-dir " + kSim + " ";
  for (const std::string bad : {"--seed -1", "--seed 1e20", "--seed 18446744073709551616"}) {  // was 2^64-1
    EXPECT_NE(run_cli(mjcf + bad, log), 0) << bad;
    EXPECT_NE(log.find("--seed: expected a whole number"), std::string::npos) << bad << ": " << log;
  }
  for (const std::string bad : {"-1", "nan", "inf", "1e9"}) {
    EXPECT_NE(run_cli(mjcf + "--stair-height " + bad, log), 0) << bad;
    EXPECT_NE(log.find("--stair-height: expected a finite number in [0, 0.3]"), std::string::npos) << bad << ": " << log;
  }
  EXPECT_EQ(run_cli(mjcf + "--seed 3 --stair-height 0.06 > /dev/null", log), 0) << log;
}

TEST(Inputs, MissingDirectoriesDirectoriesAsFilesAndHugeFilesAreRefused) {
  std::string log;
  EXPECT_EQ(exit_code(run_cli("export-mjcf --config-dir /nonexistent/sim", log)), 1);
  EXPECT_NE(log.find("/nonexistent/sim: no such config directory"), std::string::npos) << log;
  const std::string dir = temp_dir("inputs");
  EXPECT_EQ(exit_code(run_cli("train --config " + dir + " --out " + dir + "/run", log)), 1);
  EXPECT_NE(log.find(dir + ": is a directory, expected a file"), std::string::npos) << log;
  EXPECT_EQ(exit_code(run_cli("config validate " + dir, log)), 1);
  EXPECT_NE(log.find("is a directory"), std::string::npos) << log;
  // 50 MB of configuration: refused before parsing, and not echoed.
  const std::string huge = dir + "/huge.yaml";
  std::ofstream(huge) << "trainer:\n  mode: " << std::string(50u << 20, 'h') << "\n";
  EXPECT_EQ(exit_code(run_cli("train --config " + huge + " --out " + dir + "/run", log)), 1);
  EXPECT_NE(log.find("bytes, more than the 1048576-byte limit"), std::string::npos) << log.substr(0, 300);
  EXPECT_LT(log.size(), 400u);
  fs::remove(huge);
  // A long bad value is quoted short.
  EXPECT_EQ(exit_code(run_cli("train " + kTinyRun + " --set trainer.mode=" + std::string(5000, 'm') + " --out " +
                                  dir + "/run",
                              log)),
            1);
  EXPECT_NE(log.find("characters)"), std::string::npos) << log.substr(0, 300);
  EXPECT_LT(log.size(), 400u);
  // A key given twice.
  std::ofstream(dir + "/dup.yaml") << read_text(kCi) << "trainer:\n  seed: 2\n";
  EXPECT_EQ(exit_code(run_cli("train --config " + dir + "/dup.yaml --out " + dir + "/run", log)), 1);
  EXPECT_NE(log.find("key 'trainer' appears twice"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(dir + "/run"));
}

// `config validate` checks what the simulator builds, not only the file.
TEST(ConfigValidate, BuildsTheRobotTheFileDescribesAndNamesTheFault) {
  const std::string dir = temp_dir("config_validate");
  std::string log;
  ASSERT_EQ(run_shell(kExe + " config chain -n 4 > " + dir + "/chain.yaml", log), 0) << log;
  EXPECT_EQ(run_cli("config validate " + dir + "/chain.yaml --config-dir " + kSim, log), 0) << log;
  EXPECT_NE(log.find("valid, chain of 4 modules: 1-2-3-4; the simulator builds it: 17 joints, 16 actuators"),
            std::string::npos)
      << log;
  // Module 2's back face docked to module 3's back face: plates fit, but it is no chain.
  std::string c_a = "C_a:\n";
  for (int i = 0; i < 10; ++i) {
    c_a += "  - [";
    for (int j = 0; j < 10; ++j) c_a += std::string(j ? "," : "") + (std::abs(i - j) == 1 && i < 3 && j < 3 ? "1" : "0");
    c_a += "]\n";
  }
  std::ofstream(dir + "/back_to_back.yaml") << c_a << "C_s:\n  - [1,2,2,1,1]\n  - [2,3,2,2,1]\n";
  EXPECT_EQ(exit_code(run_cli("config validate " + dir + "/back_to_back.yaml --config-dir " + kSim, log)), 1);
  EXPECT_NE(log.find("is not a chain link"), std::string::npos) << log;
  fs::remove_all(dir);
}

// The data files (configs/sim, ...) are found at run time: beside the program,
// or where COMORPH_RESOURCES says; a program that finds none says where it looked.
TEST(Resources, FoundBesideTheProgramOrThroughTheEnvironmentAndNamedWhenMissing) {
  const std::string dir = temp_dir("resources");
  std::string log;
  ASSERT_EQ(run_shell(kExe + " config chain -n 3 > " + dir + "/chain.yaml", log), 0) << log;
  // No --config-dir: the build's own data files.
  EXPECT_EQ(run_cli("config validate " + dir + "/chain.yaml", log), 0) << log;
  // A copy of the program far from any data files, run from a directory without them.
  fs::create_directories(dir + "/bin");
  fs::copy_file(kExe, dir + "/bin/comorph");
  const auto moved = [&](const std::string& environment) {
    return "cd " + dir + " && " + environment + " " + dir + "/bin/comorph config validate chain.yaml";
  };
  EXPECT_EQ(exit_code(run_shell(moved(""), log)), 1);
  EXPECT_NE(log.find("set COMORPH_RESOURCES"), std::string::npos) << log;
  EXPECT_NE(log.find(dir + "/bin/comorph"), std::string::npos) << log;
  EXPECT_EQ(run_shell(moved("COMORPH_RESOURCES=" + std::string(COMORPH_SOURCE_DIR)), log), 0) << log;
  EXPECT_NE(log.find("valid, chain of 3 modules"), std::string::npos) << log;
  // A COMORPH_RESOURCES without the files is named, not searched past.
  EXPECT_EQ(exit_code(run_shell(moved("COMORPH_RESOURCES=" + dir), log)), 1);
  EXPECT_NE(log.find("COMORPH_RESOURCES=" + dir + " does not hold configs/sim/robot.yaml"), std::string::npos) << log;
  fs::remove_all(dir);
}

}  // namespace
