// What the trainer refuses instead of using (docs/faults.md): damaged checkpoints
// (checksums, with the fallback to checkpoint.old), torch load errors as one
// line, counts that do not fit the config, a changed simulator config, a
// checkpoint write that fails (the last good checkpoint stays), and the
// config's range, section and duplicate-key checks.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <atomic>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>
#include <string>
#include <vector>

#include "common/checksum.hpp"
#include "coopt/config.hpp"
#include "coopt/trainer.hpp"
#include "support/test_support.hpp"

namespace comorph::coopt {
namespace {
namespace fs = std::filesystem;

const std::string kCi = std::string(COMORPH_SOURCE_DIR) + "/configs/ci.yaml";
const std::string kSim = std::string(COMORPH_SOURCE_DIR) + "/configs/sim";

using test_support::error_of;

// A finished ci run (warm-up 2 + 2 episodes, checkpoints after 2 and 4), so
// that checkpoint/ counts 4 episodes and checkpoint.old/ 2.
std::string trained_run(const std::string& name, const std::vector<std::string>& sets = {}) {
  const std::string dir = test_support::fresh_temp_dir("reliability_" + name);
  std::vector<std::string> all{"trainer.episodes=2", "trainer.eval_interval=0"};
  all.insert(all.end(), sets.begin(), sets.end());
  Trainer t(load_coopt_config(kCi, all), dir);
  EXPECT_TRUE(t.run());
  return dir;
}
const std::vector<std::string> kRunSets{"trainer.episodes=2", "trainer.eval_interval=0"};

void flip_byte(const std::string& path, std::streamoff at) {
  std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
  f.seekg(at);
  const char c = static_cast<char>(f.get());
  f.seekp(at);
  f.put(static_cast<char>(c ^ 0x5a));
}

// Rewrites one line of a checkpoint's trainer.yaml and its checksums (as a
// consistent but wrong checkpoint would be).
void edit_trainer_yaml(const std::string& checkpoint, const std::string& from, const std::string& to) {
  const std::string path = checkpoint + "/trainer.yaml";
  std::string text = test_support::read_text(path);
  const auto at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
  std::ofstream(path, std::ios::trunc) << text;
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(checkpoint))
    if (e.path().filename() != kChecksumFile) names.push_back(e.path().filename().string());
  write_checksums(checkpoint, names);
}

TEST(Checkpoint, CarriesChecksumsAndKeepsThePreviousOne) {
  const std::string dir = trained_run("sums");
  EXPECT_EQ(verify_checksums(dir + "/checkpoint"), "");
  EXPECT_EQ(verify_checksums(dir + "/checkpoint.old"), "");
  EXPECT_EQ(read_checkpoint_info(dir).episodes, 4);
  // A checkpoint whose checksum file was deleted is not verified, so not used.
  fs::remove(dir + "/checkpoint/" + kChecksumFile);
  EXPECT_EQ(read_checkpoint_info(dir).directory, dir + "/checkpoint.old");
  fs::remove(dir + "/checkpoint.old/" + kChecksumFile);
  const std::string e = error_of([&] { read_checkpoint_info(dir); });
  EXPECT_NE(e.find(dir + "/checkpoint/checksums.txt: missing"), std::string::npos) << e;
  fs::remove_all(dir);
}

TEST(Checkpoint, AFlippedByteIsFoundAndThePreviousCheckpointIsUsed) {
  const std::string dir = trained_run("flip");
  flip_byte(dir + "/checkpoint/motion_actor.pt", 200);
  const CheckpointInfo info = read_checkpoint_info(dir);
  EXPECT_EQ(info.directory, dir + "/checkpoint.old");
  EXPECT_EQ(info.episodes, 2);
  // It resumes from there and trains the lost episodes again.
  Trainer t(load_coopt_config(kCi, kRunSets), dir);
  t.resume();
  EXPECT_EQ(t.episodes_done(), 2);
  // Both damaged: refused, naming the file.
  flip_byte(dir + "/checkpoint.old/config_model.pt", 100);
  const std::string e = error_of([&] { read_checkpoint_info(dir); });
  EXPECT_NE(e.find(dir + "/checkpoint/motion_actor.pt: checksum mismatch"), std::string::npos) << e;
  EXPECT_NE(e.find(dir + "/checkpoint.old/config_model.pt: checksum mismatch"), std::string::npos) << e;
  fs::remove_all(dir);
}

// The replay segments are files of the checkpoint like the others: a damaged
// segment that only the newest checkpoint holds makes the reader fall back to
// checkpoint.old; one that both share (hard links of one file) is named in
// both, and nothing is loaded.
TEST(Checkpoint, ADamagedReplaySegmentFallsBackOrIsNamedInBoth) {
  const std::string dir = trained_run("segment");
  std::vector<std::string> newest, shared;
  for (const auto& e : fs::directory_iterator(dir + "/checkpoint")) {
    const std::string name = e.path().filename().string();
    if (name.find("-replay-") == std::string::npos) continue;
    (fs::exists(dir + "/checkpoint.old/" + name) ? shared : newest).push_back(name);
  }
  ASSERT_FALSE(newest.empty());
  ASSERT_FALSE(shared.empty());
  flip_byte(dir + "/checkpoint/" + newest.front(), 100);
  const CheckpointInfo info = read_checkpoint_info(dir);
  EXPECT_EQ(info.directory, dir + "/checkpoint.old");
  EXPECT_EQ(info.episodes, 2);
  flip_byte(dir + "/checkpoint/" + shared.front(), 100);
  const std::string e = error_of([&] { read_checkpoint_info(dir); });
  EXPECT_NE(e.find(dir + "/checkpoint/"), std::string::npos) << e;
  EXPECT_NE(e.find(dir + "/checkpoint.old/" + shared.front() + ": checksum mismatch"), std::string::npos) << e;
  fs::remove_all(dir);
}

TEST(Checkpoint, ATorchLoadErrorIsOneLineNamingTheFile) {
  const std::string dir = trained_run("truncated");
  fs::remove_all(dir + "/checkpoint.old");
  const std::string file = dir + "/checkpoint/motion.pt";
  fs::resize_file(file, 100);
  // Truncated with matching checksums (e.g. written so by a broken disk): torch must refuse it.
  edit_trainer_yaml(dir + "/checkpoint", "episodes: 4", "episodes: 4");
  Trainer t(load_coopt_config(kCi, kRunSets), dir);
  const std::string e = error_of([&] { t.resume(); });
  EXPECT_EQ(e.rfind(file + ": cannot load: ", 0), 0u) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  EXPECT_EQ(e.find("Exception raised from"), std::string::npos) << e;  // no C++ backtrace
  fs::remove_all(dir);
}

TEST(Checkpoint, CountsThatDoNotFitTheConfigAreRefusedWithTheNumbers) {
  const std::string dir = trained_run("counts");
  fs::remove_all(dir + "/checkpoint.old");
  const CooptConfig c = load_coopt_config(kCi, kRunSets);
  edit_trainer_yaml(dir + "/checkpoint", "episodes: 4", "episodes: 999");
  std::string e = error_of([&] { Trainer(c, dir).resume(); });
  EXPECT_NE(e.find("the checkpoint counts 999 episodes, the config has 4"), std::string::npos) << e;
  edit_trainer_yaml(dir + "/checkpoint", "episodes: 999", "episodes: -5");
  e = error_of([&] { Trainer(c, dir).resume(); });
  EXPECT_NE(e.find("the checkpoint counts -5 episodes"), std::string::npos) << e;
  EXPECT_NE(e.find("refusing to resume"), std::string::npos) << e;
  fs::remove_all(dir);
}

// The simulator config is part of the run's identity: an edited robot.yaml
// between train and resume is refused, naming the file and the line; an
// edited comment is not a change.
TEST(Checkpoint, AChangedSimulatorConfigIsRefusedOnResume) {
  const std::string env = test_support::fresh_temp_dir("reliability_simcopy");
  fs::copy(kSim, env, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
  const std::string dir = trained_run("env", {"trainer.env_dir=" + env});
  const std::vector<std::string> sets{"trainer.episodes=2", "trainer.eval_interval=0", "trainer.env_dir=" + env};
  std::ofstream(env + "/robot.yaml", std::ios::app) << "# a comment changes nothing\n";
  EXPECT_EQ(error_of([&] { Trainer(load_coopt_config(kCi, sets), dir).resume(); }), "");

  std::string robot = test_support::read_text(env + "/robot.yaml");
  const std::regex wheel("wheel_radius: *[0-9.]+");
  ASSERT_TRUE(std::regex_search(robot, wheel));
  robot = std::regex_replace(robot, wheel, "wheel_radius: 0.07");
  std::ofstream(env + "/robot.yaml", std::ios::trunc) << robot;
  const CooptConfig edited = load_coopt_config(kCi, sets);
  const std::string e = error_of([&] { Trainer(edited, dir).resume(); });
  EXPECT_NE(e.find("the simulator config (" + env + ") changed"), std::string::npos) << e;
  EXPECT_NE(e.find("wheel_radius: 0.07"), std::string::npos) << e;
  EXPECT_NE(e.find("refusing to resume"), std::string::npos) << e;
  // Evaluating it under other physics is refused too.
  EvalRequest one;
  one.episodes = one.seed = one.workers = 1;
  EXPECT_NE(error_of([&] { evaluate(edited, dir, one); }).find("changed"),
            std::string::npos);
  fs::remove_all(dir);
  fs::remove_all(env);
}

// A checkpoint write that fails (here a file-size limit, as a full disk would)
// names the file and the reason; the last good checkpoint stays and resumes.
TEST(Checkpoint, AFailedWriteKeepsTheLastGoodCheckpoint) {
  const std::string dir = test_support::fresh_temp_dir("reliability_full");
  const CooptConfig c = load_coopt_config(kCi, kRunSets);
  {  // Ctrl-C after its second episode: checkpointed there.
    std::atomic<bool> stop{false};
    TrainerCallbacks cb;
    cb.on_episode = [&stop](const EpisodeLog& l) { stop = l.episode == 1; };
    Trainer first(c, dir, cb);
    EXPECT_FALSE(first.run(&stop));
  }
  // Resumed and asked to stop before its next episode: run() writes a
  // checkpoint at once, and that write fails.
  Trainer t(c, dir);
  t.resume();
  std::atomic<bool> stop{true};
  std::signal(SIGXFSZ, SIG_IGN);
  rlimit saved{};
  getrlimit(RLIMIT_FSIZE, &saved);
  rlimit small = saved;
  small.rlim_cur = 16384;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  const std::string e = error_of([&] { t.run(&stop); });
  setrlimit(RLIMIT_FSIZE, &saved);
  std::signal(SIGXFSZ, SIG_DFL);
  EXPECT_NE(e.find("cannot write " + dir + "/checkpoint.tmp/motion.pt: File too large"), std::string::npos) << e;
  EXPECT_FALSE(fs::exists(dir + "/checkpoint.tmp"));
  EXPECT_EQ(verify_checksums(dir + "/checkpoint"), "");
  Trainer again(c, dir);
  again.resume();
  EXPECT_EQ(again.episodes_done(), 2);
  fs::remove_all(dir);
}

// A trainer that is not resumed does not start a finished run over: its
// episodes.csv and checkpoint stay as they were.
TEST(Checkpoint, RunWithoutResumeOnAnExistingRunIsRefused) {
  const std::string dir = trained_run("again");
  const std::string episodes = test_support::read_text(dir + "/episodes.csv");
  Trainer t(load_coopt_config(kCi, kRunSets), dir);
  EXPECT_NE(error_of([&] { t.run(); }).find("already holds a run"), std::string::npos);
  EXPECT_EQ(test_support::read_text(dir + "/episodes.csv"), episodes);
  EXPECT_EQ(read_checkpoint_info(dir).episodes, 4);
  fs::remove_all(dir);
}

// --- settings ---------------------------------------------------------------

std::string config_error(const std::vector<std::string>& sets) {
  return error_of([&] { load_coopt_config(kCi, sets); });
}

TEST(Settings, LearnerValuesOutsideTheirRangesAreRefused) {
  EXPECT_NE(config_error({"td3.gamma=1.5"}).find("td3: field 'gamma': value 1.5 out of range [0, 1]"),
            std::string::npos);
  EXPECT_NE(config_error({"td3.tau=1.5"}).find("field 'tau'"), std::string::npos);
  EXPECT_NE(config_error({"dqn.epsilon_start=1.5"}).find("field 'epsilon_start'"), std::string::npos);
  EXPECT_NE(config_error({"dqn.learning_rate=.nan"}).find("field 'learning_rate'"), std::string::npos);
  EXPECT_NE(config_error({"td3.actor_learning_rate=.inf"}).find("field 'actor_learning_rate'"), std::string::npos);
  EXPECT_NE(config_error({"sac.alpha=-1"}).find("field 'alpha'"), std::string::npos);
  EXPECT_NE(config_error({"td3.hidden_sizes=[32, 0]"}).find("layer width 0"), std::string::npos);
  EXPECT_EQ(config_error({"td3.gamma=1.0", "td3.tau=1.0"}), "");
}

TEST(Settings, AnUnavailableDeviceIsAClearError) {
  const std::string e = config_error({"td3.device=cuda:3"});
  // This LibTorch may or may not have CUDA; either way no raw library error.
  EXPECT_NE(e.find("torch device \"cuda:3\" is not available"), std::string::npos) << e;
  EXPECT_NE(config_error({"dqn.device=tpu"}).find("unknown torch device \"tpu\""), std::string::npos);
}

TEST(Settings, ZeroEpisodesWithZeroWarmupIsRefused) {
  EXPECT_NE(config_error({"trainer.episodes=0", "trainer.warmup_episodes=0"})
                .find("field 'trainer.episodes': warmup_episodes + episodes must be at least 1"),
            std::string::npos);
}

TEST(Settings, ScanSteeringWithoutTheScanIsRefused) {
  const std::string e = config_error({"trainer.pilot_flat_steering=scan", "env.robot.scan_columns=0"});
  EXPECT_NE(e.find("trainer.pilot_flat_steering: scan needs env.robot.scan_columns > 0"), std::string::npos) << e;
  EXPECT_NE(config_error({"trainer.pilot_flat_steering=lidar"}).find("pilot_flat_steering"), std::string::npos);
  EXPECT_EQ(config_error({"trainer.pilot_flat_steering=scan", "env.robot.scan_columns=24"}), "");
  const std::string stairs = config_error({"trainer.pilot_stair_steering=scan", "env.robot.scan_columns=0"});
  EXPECT_NE(stairs.find("trainer.pilot_stair_steering: scan needs env.robot.scan_columns > 0"), std::string::npos)
      << stairs;
  EXPECT_NE(config_error({"trainer.pilot_stair_steering=sideways"}).find("pilot_stair_steering"), std::string::npos);
}

TEST(Settings, AMissingLearnerSectionIsNamed) {
  const std::string e = error_of([] { coopt_config_from_text("trainer:\n  episodes: 2\n", "bare.yaml"); });
  EXPECT_NE(e.find("bare.yaml: no 'td3:' section: trainer.motion_algo td3 needs the motion model's"),
            std::string::npos)
      << e;
  const std::string d = error_of([] { coopt_config_from_text("td3:\n  random_action_steps: 0\n", "nodqn.yaml"); });
  EXPECT_NE(d.find("no 'dqn:' section: trainer.mode hierarchical"), std::string::npos) << d;
  EXPECT_EQ(error_of([] {
              coopt_config_from_text("trainer: {mode: fixed}\ntd3: {random_action_steps: 0}\n", "fixed.yaml");
            }),
            "");
}

TEST(Settings, DuplicateKeysAndConfigFilesThatAreNotFilesAreRefused) {
  const std::string e = error_of([] { coopt_config_from_text("trainer:\n  seed: 1\n  seed: 2\n", "dup.yaml"); });
  EXPECT_NE(e.find("dup.yaml: key 'seed' appears twice in one mapping (line 3)"), std::string::npos) << e;
  const std::string dir = test_support::fresh_temp_dir("reliability_dirconfig");
  EXPECT_NE(error_of([&] { load_coopt_config(dir); }).find(dir + ": is a directory, expected a file"),
            std::string::npos);
  EXPECT_NE(error_of([&] { load_coopt_config(dir + "/none.yaml"); }).find("no such file"), std::string::npos);
  EXPECT_NE(config_error({"trainer.env_dir=" + dir + "/missing"}).find("no such config directory"),
            std::string::npos);
}

}  // namespace
}  // namespace comorph::coopt
