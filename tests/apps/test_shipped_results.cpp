// The trained policies that ship in results/ (docs/results.md) still work with
// today's simulator: the standard preset's hierarchical run, evaluated
// greedily on 30 episodes (10 per stair height, on seeds no training or tuning
// used), must reach 75 % average success. A change of the physics, sensors or
// controller that breaks the policy fails here until it is trained again.
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
    for (const char* name : {"config.yaml", "run.yaml", "episodes.csv", "checkpoint/trainer.yaml",
                             "checkpoint/motion_actor.pt", "checkpoint/checksums.txt"})
      EXPECT_TRUE(fs::exists(run.path() / name)) << run.path() / name;
    EXPECT_FALSE(fs::exists(run.path() / "checkpoint" / "motion.pt")) << "a replay buffer ships in " << run.path();
  }
}

TEST(ShippedResults, StandardHierarchicalPolicyStillSucceeds) {
  ASSERT_TRUE(fs::exists(kShipped / "checkpoint" / "motion_actor.pt")) << kShipped;
  const fs::path work = fresh_temp_dir("shipped");
  fs::copy(kShipped, work / "run", fs::copy_options::recursive);
  // The run's switches come from the scene classifier in runs/classifier (relative
  // to the working directory); `classifier prepare` is seeded and makes the same
  // weights every time, so it is trained here rather than shipped (2.8 MB).
  ASSERT_EQ(run_in(work, "classifier prepare --out runs/classifier --config " +
                             (kSource / "configs" / "perception.yaml").string() + " --config-dir " +
                             (kSource / "configs" / "sim").string()),
            0)
      << read_text(work / "log.txt");
  ASSERT_EQ(run_in(work, "eval --run run --episodes 30 --seed 8100000 --workers 2"), 0) << read_text(work / "log.txt");
  EXPECT_NE(read_text(work / "log.txt").find("eval default: 30/30 episodes"), std::string::npos)  // the last progress line
      << read_text(work / "log.txt");
  const nlohmann::json j = nlohmann::json::parse(read_text(work / "run" / "eval-default.json"));
  const double success = j["success_rate"]["avg"].get<double>();
  std::printf("shipped standard hierarchical policy: %.1f %% success on 30 episodes (seeds 8100000..8100029)\n",
              100 * success);
  EXPECT_GE(success, 0.75) << read_text(work / "log.txt");
  fs::remove_all(work);
}

}  // namespace
