// `comorph experiment` on the ci preset: every column of Table II becomes its
// own run directory with its evaluations, the combined table holds our numbers
// beside the paper's, a second call trains nothing again, and a call with a
// changed configuration is refused instead of mixing two configurations.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>

#include <algorithm>
#include <filesystem>
#include <string>

#include "common/file_io.hpp"
#include "support/test_support.hpp"

namespace {
namespace fs = std::filesystem;

const std::string kCi = std::string(COMORPH_SOURCE_DIR) + "/configs/ci.yaml";

using comorph::test_support::read_text;
int run_cli(const std::string& args, std::string& output) { return comorph::test_support::run_comorph(args, output); }

TEST(Experiment, Table2TrainsEveryColumnWritesTheTableAndResumesWithoutRetraining) {
  const fs::path out = fs::temp_directory_path() / ("comorph_experiment_" + std::to_string(::getpid()));
  fs::remove_all(out);
  const std::string command =
      "experiment --table 2 --config " + kCi + " --eval-episodes 3 --out " + out.string();
  std::string log;
  ASSERT_EQ(run_cli(command, log), 0) << log;

  // Table II: the TD3 hierarchy (default, 7 and 8 obstacles), the one trained
  // on the mixed scene (evaluated there) and the SAC hierarchy.
  for (const char* f : {"hier-td3/eval-default.json", "hier-td3/eval-obstacles7.json", "hier-td3/eval-obstacles8.json",
                        "hier-td3-mixed/eval-mixed.json", "hier-sac/eval-default.json", "table-2.md",
                        "report/report.md", "report/report.html"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  EXPECT_FALSE(fs::exists(out / "fixed-2"));  // Table I's columns are not Table II's
  EXPECT_FALSE(fs::exists(out / "hier-td3/eval-mixed.json"));
  EXPECT_NE(read_text(out / "hier-sac/run.yaml").find("algo: sac"), std::string::npos);
  EXPECT_NE(read_text(out / "hier-td3-mixed/run.yaml").find("scenario: mixed"), std::string::npos);
  const std::string table = read_text(out / "table-2.md");
  for (const char* cell :
       {"SAC, default [hier-sac]", "TD3, 8 obstacles [hier-td3]", "TD3, mixed [", "/ 3.24", "/ 89.3", "F(H)"})
    EXPECT_NE(table.find(cell), std::string::npos) << cell << " not in\n" << table;
  EXPECT_EQ(table.find("—"), std::string::npos) << "a column has no run:\n" << table;
  // The report of the tiny runs: both tables, a section per run, the training curves.
  const std::string report = read_text(out / "report/report.md");
  for (const char* part : {"## Table I:", "## Table II:", "SAC, default [hier-sac]", "### hier-td3", "### hier-sac",
                           "(training-curves.png)"})
    EXPECT_NE(report.find(part), std::string::npos) << part << " not in the report";
  ASSERT_TRUE(fs::exists(out / "report/training-curves.png"));
  EXPECT_GT(fs::file_size(out / "report/training-curves.png"), 1000u);

  // Again: nothing is trained or evaluated twice.
  const std::string episodes = read_text(out / "hier-td3/episodes.csv");
  const auto eval_time = fs::last_write_time(out / "hier-sac/eval-default.json");
  ASSERT_EQ(run_cli(command, log), 0) << log;
  EXPECT_NE(log.find("done before"), std::string::npos) << log;
  EXPECT_EQ(read_text(out / "hier-td3/episodes.csv"), episodes);
  EXPECT_EQ(fs::last_write_time(out / "hier-sac/eval-default.json"), eval_time);

  // A changed configuration is refused, naming the column's directory.
  EXPECT_NE(run_cli(command + " --set trainer.episodes=5", log), 0);
  EXPECT_NE(log.find("another configuration"), std::string::npos) << log;
  EXPECT_NE(log.find("hier-td3"), std::string::npos) << log;
  fs::remove_all(out);
}

// A preset with a DQN refit (configs/standard.yaml) still has fixed columns: a
// fixed chain has no DQN, so its motion model trains for the hierarchy's
// warm-up and training episodes and nothing is refitted (its dqn_refit: unused).
TEST(Experiment, FixedColumnOfAPresetWithADqnRefitTrainsTheMotionBudgetOnly) {
  const fs::path out = fs::temp_directory_path() / ("comorph_experiment_refit_" + std::to_string(::getpid()));
  fs::remove_all(out);
  std::string log;
  ASSERT_EQ(run_cli("experiment --table 1 --only fixed-2 --config " + kCi +
                        " --set trainer.config_refit_episodes=3 --set dqn_refit.loss=mse --eval-episodes 3 --eval-seed 8123000 --out " +
                        out.string(),
                    log),
            0)
      << log;
  const std::string episodes = read_text(out / "fixed-2/episodes.csv");
  EXPECT_EQ(std::count(episodes.begin(), episodes.end(), '\n'), 1 + 2 + 4);  // header, ci.yaml's 2 + 4 episodes
  EXPECT_NE(read_text(out / "fixed-2/config.yaml").find("config_refit_episodes: 0"), std::string::npos);
  EXPECT_TRUE(fs::exists(out / "fixed-2/eval-default.json"));
  // --eval-seed: the evaluation's episodes start at that seed, not at eval.seed.
  EXPECT_NE(read_text(out / "fixed-2/eval-default-episodes.csv").find("\n0,8123000,default,"), std::string::npos);
  fs::remove_all(out);
}

TEST(Experiment, BadTableOrColumnIsNamedBeforeAnyTraining) {
  const fs::path out = fs::temp_directory_path() / ("comorph_experiment_bad_" + std::to_string(::getpid()));
  fs::remove_all(out);
  std::string log;
  EXPECT_NE(run_cli("experiment --table 3 --config " + kCi + " --out " + out.string(), log), 0);
  EXPECT_NE(log.find("--table must be 1 or 2"), std::string::npos) << log;
  EXPECT_NE(run_cli("experiment --table 1 --only fixed-3 --config " + kCi + " --out " + out.string(), log), 0);
  EXPECT_NE(log.find("fixed-4"), std::string::npos) << log;  // the message lists the columns
  EXPECT_NE(run_cli("experiment --table 1 --set trainer.epsiodes=2 --config " + kCi + " --out " + out.string(), log), 0);
  EXPECT_NE(log.find("trainer.epsiodes"), std::string::npos) << log;
  for (const char* seeds : {"2-x", "3-1", "0", "1,1-2", ""}) {
    EXPECT_NE(run_cli("experiment --table 1 --seeds '" + std::string(seeds) + "' --config " + kCi + " --out " +
                          out.string(),
                      log),
              0);
    EXPECT_NE(log.find("--seeds"), std::string::npos) << seeds << ": " << log;
  }
  EXPECT_NE(run_cli("experiment --table 1 --out " + out.string(), log), 0);
  EXPECT_NE(log.find("give --config"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(out));
}

// --seeds: a run directory per column and seed, trained with that seed; the
// table shows the column's mean [min, max] over them and names the runs
// still missing; --collect makes the same table from what exists.
TEST(Experiment, SeedsAreRunsOfTheirOwnAndTheTableNamesWhatIsMissing) {
  const fs::path out = fs::temp_directory_path() / ("comorph_experiment_seeds_" + std::to_string(::getpid()));
  fs::remove_all(out);
  std::string log;
  ASSERT_EQ(run_cli("experiment --table 1 --only fixed-2 --seeds 1,3 --config " + kCi +
                        " --set trainer.eval_interval=0 --eval-episodes 3 --out " + out.string(),
                    log),
            0)
      << log;
  for (int seed : {1, 3}) {
    const fs::path run = out / ("fixed-2-seed-" + std::to_string(seed));
    EXPECT_TRUE(fs::exists(run / "eval-default.json")) << run;
    EXPECT_TRUE(fs::exists(run / "finished")) << run;
    EXPECT_NE(read_text(run / "config.yaml").find("  seed: " + std::to_string(seed) + "\n"), std::string::npos);
  }
  EXPECT_NE(read_text(out / "fixed-2-seed-1/episodes.csv"), read_text(out / "fixed-2-seed-3/episodes.csv"));
  const std::string table = read_text(out / "table-1.md");
  for (const char* part : {"Fixed 2 [2 runs]", "| 1, 3 / n/a", "Missing, so not in the table: ",
                           "fixed-4-seed-3: not started", "hier-td3-seed-1: not started"})
    EXPECT_NE(table.find(part), std::string::npos) << part << " not in\n" << table;
  EXPECT_EQ(table.find("fixed-2-seed-1:"), std::string::npos) << table;
  EXPECT_NE(read_text(out / "report/report.md").find("fixed-4-seed-3: not started"), std::string::npos);

  // A run stopped before its end is named with how far it got.
  fs::remove(out / "fixed-2-seed-3/eval-default.json");
  ASSERT_EQ(run_cli("experiment --table 1 --seeds 1,3 --out " + out.string() + " --collect", log), 0) << log;
  const std::string collected = read_text(out / "table-1.md");
  EXPECT_NE(collected.find("Fixed 2 [fixed-2-seed-1]"), std::string::npos) << collected;
  EXPECT_NE(collected.find("(1 seed) / 24.2"), std::string::npos) << collected;
  EXPECT_NE(collected.find("fixed-2-seed-3: trained, not evaluated on default"), std::string::npos) << collected;
  fs::remove_all(out);
}

// The published tables over runs that exist (results/, one seed each): every
// Table I column from its shipped run, each cell marked as one seed's.
TEST(Experiment, CollectsShippedRunsMarkingSingleSeedCells) {
  const fs::path out = fs::temp_directory_path() / ("comorph_experiment_collect_" + std::to_string(::getpid()));
  fs::remove_all(out);
  const std::string results = std::string(COMORPH_SOURCE_DIR) + "/results/";
  std::string runs;
  for (const char* r : {"standard-hier-td3", "fixed-2", "fixed-4", "fixed-6", "fixed-8", "fixed-10"})
    runs += " " + results + r;
  std::string log;
  ASSERT_EQ(run_cli("experiment --table 1 --collect --out " + out.string() + " --runs" + runs, log), 0) << log;
  const std::string table = read_text(out / "table-1.md");
  // results/fixed-2: 97 % at 0.04 m, 32.3 % on average (its eval-default.json).
  for (const char* part : {"Ours (hierarchical) [hier-td3]", "Fixed 2 [fixed-2]", "| 97.0 (1 seed) / 72.5",
                           "| 32.3 (1 seed) / 24.2", "| 1 / n/a"})
    EXPECT_NE(table.find(part), std::string::npos) << part << " not in\n" << table;
  EXPECT_EQ(table.find("—"), std::string::npos) << table;
  EXPECT_EQ(table.find("Missing"), std::string::npos) << table;
  EXPECT_TRUE(fs::exists(out / "report/report.html"));
  // A run that is not one is named, the others still make the table; a run
  // named twice is one seed.
  ASSERT_EQ(run_cli("experiment --table 1 --collect --out " + out.string() + " --runs " + out.string() + runs + " " +
                        results + "fixed-2/",
                    log),
            0)
      << log;
  const std::string again = read_text(out / "table-1.md");
  EXPECT_NE(again.find("Missing, so not in the table: run directory " + out.string()), std::string::npos) << again;
  EXPECT_NE(again.find("| 32.3 (1 seed) / 24.2"), std::string::npos) << again;
  fs::remove_all(out);
}

// The matrix is the data of configs/reference/paper-tables.yaml: a column
// added there (a fixed chain of 3 modules) is a column of the experiment, its
// keys built from its `match`, and a column whose match cannot be trained is
// refused naming the file and the column.
TEST(Experiment, ColumnsComeFromThePaperTablesFile) {
  const fs::path resources = fs::temp_directory_path() / ("comorph_experiment_data_" + std::to_string(::getpid()));
  fs::remove_all(resources);
  fs::create_directories(resources);
  fs::copy(std::string(COMORPH_SOURCE_DIR) + "/configs", resources / "configs", fs::copy_options::recursive);
  const fs::path tables = resources / "configs/reference/paper-tables.yaml";
  std::string text = read_text(tables);
  const std::string fixed2 = "      - label: \"Fixed 2\"\n";
  const auto at = text.find(fixed2);
  ASSERT_NE(at, std::string::npos);
  text.insert(at, "      - label: \"Fixed 3\"\n        match: {kind: fixed, modules: 3, algo: td3, eval: default}\n");
  comorph::write_file_atomic(tables.string(), text);

  const std::string command = "experiment --table 1 --only fixed-3 --config " + kCi + " --out " +
                              (resources / "out").string() + " --set trainer.epsiodes=2";
  std::string log;
  // The repository's file has no such column.
  EXPECT_NE(run_cli(command, log), 0);
  EXPECT_NE(log.find("has no column 'fixed-3'"), std::string::npos) << log;
  // With the edited file the call gets past the column, as far as its keys.
  ::setenv("COMORPH_RESOURCES", resources.c_str(), 1);
  EXPECT_NE(run_cli(command, log), 0);
  EXPECT_EQ(log.find("no column"), std::string::npos) << log;
  EXPECT_NE(log.find("trainer.epsiodes"), std::string::npos) << log;

  // A fixed column without a module count cannot be trained: named with the file.
  text.replace(text.find("{kind: fixed, modules: 3,"), 25, "{kind: fixed,");
  comorph::write_file_atomic(tables.string(), text);
  EXPECT_NE(run_cli(command, log), 0);
  EXPECT_NE(log.find("paper-tables.yaml: table 1, column 'Fixed 3'"), std::string::npos) << log;
  ::unsetenv("COMORPH_RESOURCES");
  fs::remove_all(resources);
}

}  // namespace
