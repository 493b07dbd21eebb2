// The paper's tables as kept in configs/reference/paper-tables.yaml.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "report/metrics.hpp"
#include "report/paper_reference.hpp"

namespace comorph::report {
namespace {

TEST(PaperReference, LoadsBothTablesInThePapersLayout) {
  const PaperReference ref = load_paper_reference(COMORPH_TEST_REFERENCE);
  ASSERT_EQ(ref.tables.size(), 2u);
  EXPECT_EQ(ref.tables[0].id, 1);
  ASSERT_EQ(ref.tables[0].columns.size(), 6u);  // hierarchy, fixed 2, 4, 6, 8, 10
  EXPECT_EQ(ref.tables[0].columns[0].match.kind, "hierarchical");
  for (size_t c = 1; c < 6; ++c) {
    EXPECT_EQ(ref.tables[0].columns[c].match.kind, "fixed");
    EXPECT_EQ(ref.tables[0].columns[c].match.modules, static_cast<int>(2 * c));
  }
  EXPECT_EQ(ref.tables[1].id, 2);
  EXPECT_EQ(ref.tables[1].columns[1].match.algo, "sac");
  EXPECT_EQ(ref.tables[1].columns[3].match.eval_scenario, "obstacles8");
  // The training scenario: default unless given (the mixed column's run trains on the mixed scene).
  EXPECT_EQ(ref.tables[1].columns[3].match.train_scenario, "default");
  EXPECT_EQ(ref.tables[1].columns[4].match.train_scenario, "mixed");
  EXPECT_EQ(default_paper_reference_path(), std::string(COMORPH_TEST_REFERENCE));
}

// Catches a mistyped number: the paper's avg is the mean of its three heights.
TEST(PaperReference, SuccessAverageIsTheMeanOfTheHeights) {
  for (const auto& t : load_paper_reference(COMORPH_TEST_REFERENCE).tables)
    for (const auto& c : t.columns) {
      if (c.success_percent.size() < 4) continue;
      const double mean =
          (c.success_percent.at("0.04") + c.success_percent.at("0.06") + c.success_percent.at("0.08")) / 3.0;
      EXPECT_NEAR(c.success_percent.at("avg"), mean, 0.15) << t.title << " / " << c.label;
    }
}

// The claim documented on task::ObjectiveWeights: with its defaults, F of a
// column's mean episode (its Time, Battery and Success avg as D) gives the paper's F.
TEST(PaperReference, DefaultObjectiveReproducesThePapersF) {
  int checked = 0;
  for (const auto& t : load_paper_reference(COMORPH_TEST_REFERENCE).tables)
    for (const auto& c : t.columns) {
      if (!std::isfinite(c.F)) continue;
      EpisodeRecord mean_episode;
      mean_episode.time_s = c.time_s;
      mean_episode.energy_J = c.energy_J;
      mean_episode.distance_fraction = c.success_percent.at("avg") / 100.0;
      EXPECT_NEAR(objective_F(mean_episode, task::ObjectiveWeights{}), c.F, 0.03) << c.label;
      ++checked;
    }
  EXPECT_EQ(checked, 10);
}

TEST(PaperReference, MalformedFileNamesTheEntry) {
  const auto path = std::filesystem::temp_directory_path() / "comorph-bad-reference.yaml";
  std::ofstream(path) << "source: x\ntables:\n  - id: 1\n    title: T\n    columns:\n      - label: A\n        match: {kind: fixed, algo: td3}\n";
  try {
    load_paper_reference(path.string());
    FAIL() << "accepted a column without match.eval";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("tables[0].columns[0]"), std::string::npos) << msg;
    EXPECT_NE(msg.find("'eval'"), std::string::npos) << msg;
  }
  std::filesystem::remove(path);
  EXPECT_THROW(load_paper_reference("/nonexistent/paper.yaml"), std::runtime_error);
}

}  // namespace
}  // namespace comorph::report
