// `comorph export` as a user ships a run into results/: the copy holds the
// acting networks without replay or optimizers and the training log gzipped,
// and `eval`, `summarize` and `report` read it as they read the run.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include "common/gzip.hpp"
#include "support/test_support.hpp"

namespace {
namespace fs = std::filesystem;
using comorph::test_support::read_text;

const std::string kCi = std::string(COMORPH_SOURCE_DIR) + "/configs/ci.yaml";

int run_cli(const std::string& args, std::string& output) { return comorph::test_support::run_comorph(args, output); }

TEST(Export, ShipsTheNetworksAndAGzippedLogThatEvalAndReportRead) {
  const fs::path work = comorph::test_support::fresh_temp_dir("export");
  const std::string run = (work / "run").string(), out = (work / "shipped").string();
  std::string log;
  ASSERT_EQ(run_cli("train --config " + kCi + " --set trainer.episodes=2 --set trainer.eval_interval=0 --out " + run, log),
            0)
      << log;
  ASSERT_EQ(run_cli("export --run " + run + " --out " + out, log), 0) << log;
  EXPECT_NE(log.find("exported " + run + " to " + out), std::string::npos) << log;

  EXPECT_TRUE(fs::exists(fs::path(out) / "checkpoint" / "motion_actor.pt"));
  EXPECT_FALSE(fs::exists(fs::path(out) / "checkpoint" / "motion.pt")) << "a replay buffer was exported";
  EXPECT_FALSE(fs::exists(fs::path(out) / "episodes.csv"));
  ASSERT_TRUE(fs::exists(fs::path(out) / "episodes.csv.gz"));
  // The same rows as the run's log (4 = 2 warm-up + 2 training episodes, one line each, plus the header).
  const std::string packed = read_text(fs::path(out) / "episodes.csv.gz");
  const std::string text = comorph::gzip_decompress(packed, "episodes.csv.gz", 1 << 20);
  const std::string original = read_text(fs::path(run) / "episodes.csv");
  EXPECT_EQ(text.substr(0, text.find('\n')), original.substr(0, original.find('\n')));
  auto lines = [](const std::string& s) { return std::count(s.begin(), s.end(), '\n'); };
  EXPECT_EQ(lines(text), lines(original));
  EXPECT_EQ(lines(text), 5);

  // summarize and report read the gzipped log; eval runs the exported networks.
  ASSERT_EQ(run_cli("summarize " + out + "/episodes.csv.gz --out " + (work / "train.json").string(), log), 0) << log;
  EXPECT_NE(read_text(work / "train.json").find("\"success_rate\""), std::string::npos);
  ASSERT_EQ(run_cli("eval --run " + out + " --episodes 3 --seed 8100000 --workers 1", log), 0) << log;
  ASSERT_EQ(run_cli("report " + out + " --out " + (work / "report").string(), log), 0) << log;
  EXPECT_TRUE(fs::exists(work / "report" / "report.md")) << log;

  // Exporting again over the copy leaves one log, the gzipped one.
  ASSERT_EQ(run_cli("export --run " + run + " --out " + out, log), 0) << log;
  EXPECT_FALSE(fs::exists(fs::path(out) / "episodes.csv"));
}

TEST(Export, ADamagedGzippedLogIsRefusedNamingTheFile) {
  const fs::path work = comorph::test_support::fresh_temp_dir("export_damaged");
  std::ofstream(work / "episodes.csv.gz", std::ios::binary) << comorph::gzip_compress("episode,seed\n").substr(0, 12);
  std::string log;
  EXPECT_NE(run_cli("summarize " + (work / "episodes.csv.gz").string() + " --out " + (work / "x.json").string(), log), 0);
  EXPECT_NE(log.find((work / "episodes.csv.gz").string() + ": damaged gzip data"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(work / "x.json"));
}

}  // namespace
