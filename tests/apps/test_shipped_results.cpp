// The trained policies that ship in results/ (docs/results.md) still work with
// today's simulator: the standard preset's hierarchical run (TD3 + the pilot's
// labels) and the RL-only preset's (RL alone), each evaluated greedily on 30
// episodes (10 per stair height, on seeds no training or tuning used), must
// reach 75 % and 60 % average success (on the reporting sets they reach 98 %
// and 79 to 85 %; a policy that no longer climbs stays below 35 %). A change of
// the physics, sensors or controller that breaks a policy fails here until it
// is trained again.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "support/test_support.hpp"

namespace fs = std::filesystem;
using comorph::test_support::fresh_temp_dir;
using comorph::test_support::read_text;

namespace {

const fs::path kSource = COMORPH_SOURCE_DIR;
const fs::path kShipped = kSource / "results" / "standard-hier-td3";

// `comorph <args>` run in `dir`; output in dir/log.txt.
int run_in(const fs::path& dir, const std::string& args) {
  return std::system(("cd " + dir.string() + " && " + COMORPH_EXE + " " + args + " > log.txt 2>&1").c_str());
}

TEST(ShippedResults, EveryRunIsSmallAndHasWhatEvalRenderAndReportNeed) {
  ASSERT_TRUE(fs::exists(kShipped)) << kShipped;
  for (const auto& run : fs::directory_iterator(kSource / "results")) {
    if (!run.is_directory()) continue;
    std::uintmax_t bytes = 0;
    for (const auto& f : fs::recursive_directory_iterator(run.path()))
      if (f.is_regular_file()) bytes += f.file_size();
    EXPECT_LE(bytes, 2000000u) << run.path();
    for (const char* name : {"config.yaml", "run.yaml", "checkpoint/trainer.yaml", "checkpoint/motion_actor.pt",
                             "checkpoint/checksums.txt"})
      EXPECT_TRUE(fs::exists(run.path() / name)) << run.path() / name;
    // The training log: episodes.csv.gz as `comorph export` writes it, or plain episodes.csv.
    EXPECT_TRUE(fs::exists(run.path() / "episodes.csv.gz") || fs::exists(run.path() / "episodes.csv")) << run.path();
    EXPECT_FALSE(fs::exists(run.path() / "checkpoint" / "motion.pt")) << "a replay buffer ships in " << run.path();
  }
}

// The greedy success of the shipped run `name` on 30 episodes (seeds
// 8100000..8100029), evaluated in a copy beside `classifier_work`'s classifier.
double shipped_success(const fs::path& classifier_work, const std::string& name) {
  const fs::path shipped = kSource / "results" / name;
  EXPECT_TRUE(fs::exists(shipped / "checkpoint" / "motion_actor.pt")) << shipped;
  const fs::path run = classifier_work / name;
  fs::remove_all(run);
  fs::copy(shipped, run, fs::copy_options::recursive);
  EXPECT_EQ(run_in(classifier_work, "eval --run " + name + " --episodes 30 --seed 8100000 --workers 2"), 0)
      << read_text(classifier_work / "log.txt");
  EXPECT_NE(read_text(classifier_work / "log.txt").find("eval default: 30/30 episodes"), std::string::npos)
      << read_text(classifier_work / "log.txt");  // the last progress line
  const nlohmann::json j = nlohmann::json::parse(read_text(run / "eval-default.json"));
  const double success = j["success_rate"]["avg"].get<double>();
  std::printf("shipped %s: %.1f %% success on 30 episodes (seeds 8100000..8100029)\n", name.c_str(), 100 * success);
  return success;
}

class ShippedPolicies : public ::testing::Test {
 protected:
  // The runs' switches come from the scene classifier in runs/classifier
  // (relative to the working directory); `classifier prepare` is seeded and
  // makes the same weights every time, so it is trained here, once for both
  // runs, rather than shipped (2.8 MB).
  static void SetUpTestSuite() {
    work_ = fresh_temp_dir("shipped");
    prepared_ = run_in(work_, "classifier prepare --out runs/classifier --config " +
                                  (kSource / "configs" / "perception.yaml").string() + " --config-dir " +
                                  (kSource / "configs" / "sim").string()) == 0;
  }
  static void TearDownTestSuite() { fs::remove_all(work_); }
  void SetUp() override { ASSERT_TRUE(prepared_) << read_text(work_ / "log.txt"); }
  static inline fs::path work_;
  static inline bool prepared_ = false;
};

TEST_F(ShippedPolicies, StandardHierarchicalPolicyStillSucceeds) {
  EXPECT_GE(shipped_success(work_, "standard-hier-td3"), 0.75);
}

TEST_F(ShippedPolicies, RlOnlyHierarchicalPolicyStillSucceeds) {
  EXPECT_GE(shipped_success(work_, "rl-only-hier-td3"), 0.60);
}

}  // namespace
