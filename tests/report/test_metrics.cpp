// summarize() on a hand-made episode log: success per stair height and its
// mean, time and energy over successes only, F(H) of Eq. 1 worked by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "report/metrics.hpp"

namespace comorph::report {
namespace {

EpisodeRecord episode(int id, double height, bool success, const std::string& why, double time_s, double energy_J,
                      double distance, std::vector<int> configs) {
  EpisodeRecord r;
  r.episode = id;
  r.seed = 1000 + id;
  r.scenario = "default";
  r.stair_height_m = height;
  r.obstacles = 6;
  r.success = success;
  r.termination = why;
  r.time_s = time_s;
  r.energy_J = energy_J;
  r.distance_fraction = distance;
  r.return_R1 = 10.0 * id;
  r.configurations = configs;
  r.modules_total = configs.front();
  return r;
}

// 0.04 m: 1 of 2 succeed; 0.06 m: 2 of 3; 0.08 m: 0 of 1.
std::vector<EpisodeRecord> hand_log() {
  return {episode(0, 0.04, true, "success", 40, 3000, 1.0, {2, 2}),
          episode(1, 0.04, false, "collision", 112, 5000, 0.5, {2}),
          episode(2, 0.06, true, "success", 50, 6000, 1.0, {4, 2}),
          episode(3, 0.06, true, "success", 60, 8000, 1.0, {4, 2}),
          episode(4, 0.06, false, "overturn", 10, 100, 0.1, {4}),
          episode(5, 0.08, false, "timeout", 112, 9000, 0.3, {6})};
}

TEST(Metrics, SuccessRatePerHeightAndTheirMean) {
  const EvalSummary m = summarize(hand_log());
  EXPECT_EQ(m.episodes, 6);
  EXPECT_DOUBLE_EQ(m.success_rate.at("0.04"), 1.0 / 2.0);
  EXPECT_DOUBLE_EQ(m.success_rate.at("0.06"), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(m.success_rate.at("0.08"), 0.0);
  // The paper's avg is the mean of the per-height rates, not successes / episodes (0.5 here).
  EXPECT_NEAR(m.success_rate.at("avg"), (0.5 + 2.0 / 3.0 + 0.0) / 3.0, 1e-12);
  EXPECT_EQ(m.success_rate.size(), 4u);
}

TEST(Metrics, TimeAndEnergyAverageSuccessfulEpisodesOnly) {
  const EvalSummary m = summarize(hand_log());
  EXPECT_DOUBLE_EQ(m.time_s, (40.0 + 50.0 + 60.0) / 3.0);
  EXPECT_DOUBLE_EQ(m.energy_J, (3000.0 + 6000.0 + 8000.0) / 3.0);
}

TEST(Metrics, ObjectiveFByHand) {
  task::ObjectiveWeights w;
  w.w_t = 0.5;
  w.w_e = 1.5;
  w.w_d = 3.0;
  w.t_max_s = 100.0;
  w.energy_scale_J = 10000.0;
  // F = -0.5 * t/100 - 1.5 * energy/10000 + 3 * D, per episode, then the mean.
  const double by_hand[] = {
      -0.5 * 0.40 - 1.5 * 3000.0 / 10000.0 + 3.0 * 1.0,  //
      -0.5 * 1.12 - 1.5 * 5000.0 / 10000.0 + 3.0 * 0.5,  //
      -0.5 * 0.50 - 1.5 * 6000.0 / 10000.0 + 3.0 * 1.0,  //
      -0.5 * 0.60 - 1.5 * 8000.0 / 10000.0 + 3.0 * 1.0,  //
      -0.5 * 0.10 - 1.5 * 100.0 / 10000.0 + 3.0 * 0.1,   //
      -0.5 * 1.12 - 1.5 * 9000.0 / 10000.0 + 3.0 * 0.3};
  const auto log = hand_log();
  double sum = 0;
  for (size_t i = 0; i < log.size(); ++i) {
    EXPECT_NEAR(objective_F(log[i], w), by_hand[i], 1e-12) << "episode " << i;
    sum += by_hand[i];
  }
  EXPECT_NEAR(summarize(log, w).F, sum / 6.0, 1e-12);
}

TEST(Metrics, ConfigurationsPerHeightAndTerminations) {
  const EvalSummary m = summarize(hand_log());
  EXPECT_EQ(m.configurations.at("0.04").at("2->2"), 1);
  EXPECT_EQ(m.configurations.at("0.04").at("2"), 1);
  EXPECT_EQ(m.configurations.at("0.06").at("4->2"), 2);
  EXPECT_EQ(m.configurations.at("0.06").at("4"), 1);
  EXPECT_EQ(m.configurations.at("0.08").size(), 1u);
  EXPECT_EQ(m.terminations.at("success"), 3);
  EXPECT_EQ(m.terminations.at("collision"), 1);
  EXPECT_EQ(m.terminations.at("overturn"), 1);
  EXPECT_EQ(m.terminations.at("timeout"), 1);
}

TEST(Metrics, NoSuccessGivesNullTimeAndEnergy) {
  auto log = hand_log();
  std::vector<EpisodeRecord> failures = {log[1], log[4], log[5]};
  const EvalSummary m = summarize(failures);
  EXPECT_TRUE(std::isnan(m.time_s));
  EXPECT_TRUE(std::isnan(m.energy_J));
  EXPECT_DOUBLE_EQ(m.success_rate.at("avg"), 0.0);
  const nlohmann::json j = to_json(m);
  EXPECT_TRUE(j.at("time_s").is_null());
  EXPECT_TRUE(j.at("energy_J").is_null());
}

TEST(Metrics, HeightsWithoutEpisodesAreLeftOutOfTheMean) {
  auto log = hand_log();
  const EvalSummary m = summarize({log[0], log[1]}, {}, {0.04, 0.06, 0.08});  // 0.04 m only
  EXPECT_TRUE(std::isnan(m.success_rate.at("0.06")));
  EXPECT_DOUBLE_EQ(m.success_rate.at("avg"), 0.5);
  EXPECT_TRUE(to_json(m)["success_rate"]["0.08"].is_null());
}

// The configuration figures: mean first choice per height, and the share of
// the episodes that reached the flat area that ended on 2 or 3 modules.
TEST(Metrics, FirstChoicePerHeightAndSheddingAfterTheStairs) {
  std::vector<EpisodeRecord> log = hand_log();
  log[0].stairs_climbed = true;  // 2 -> 2: ends on 2
  log[2].stairs_climbed = true;  // 4 -> 2: shed
  log[3].configurations = {4, 4};
  log[3].stairs_climbed = true;  // kept 4
  const EvalSummary m = summarize(log);
  EXPECT_DOUBLE_EQ(m.first_modules.at("0.04"), 2.0);
  EXPECT_DOUBLE_EQ(m.first_modules.at("0.06"), 4.0);
  EXPECT_DOUBLE_EQ(m.first_modules.at("0.08"), 6.0);
  EXPECT_DOUBLE_EQ(m.shed_after_stairs, 2.0 / 3.0);
  const EvalSummary back = metrics_from_json(nlohmann::json::parse(to_json(m).dump()), "test");
  EXPECT_EQ(back.first_modules, m.first_modules);
  EXPECT_DOUBLE_EQ(back.shed_after_stairs, m.shed_after_stairs);
  EXPECT_TRUE(std::isnan(summarize({hand_log()[1]}).shed_after_stairs));  // nobody climbed
}

TEST(Metrics, JsonHasExactlyTheAgreedKeysAndReadsBack) {
  const EvalSummary m = summarize(hand_log());
  const nlohmann::json j = to_json(m);
  std::vector<std::string> keys;
  for (auto it = j.begin(); it != j.end(); ++it) keys.push_back(it.key());
  std::sort(keys.begin(), keys.end());
  EXPECT_EQ(keys, (std::vector<std::string>{"F", "configurations", "energy_J", "episodes", "first_modules",
                                            "shed_after_stairs", "success_rate", "terminations", "time_s"}));
  for (const char* k : {"0.04", "0.06", "0.08", "avg"}) EXPECT_TRUE(j["success_rate"].contains(k)) << k;
  EXPECT_EQ(j["configurations"]["0.06"]["4->2"], 2);

  const EvalSummary back = metrics_from_json(nlohmann::json::parse(j.dump()), "test");
  EXPECT_EQ(back.success_rate, m.success_rate);
  EXPECT_DOUBLE_EQ(back.time_s, m.time_s);
  EXPECT_DOUBLE_EQ(back.energy_J, m.energy_J);
  EXPECT_DOUBLE_EQ(back.F, m.F);
  EXPECT_EQ(back.configurations, m.configurations);
  EXPECT_EQ(back.terminations, m.terminations);
  EXPECT_EQ(back.episodes, m.episodes);
}

TEST(Metrics, JsonMissingKeyIsNamed) {
  nlohmann::json j = to_json(summarize(hand_log()));
  j.erase("energy_J");
  try {
    metrics_from_json(j, "runs/x/eval-default.json");
    FAIL() << "accepted a summary without energy_J";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("runs/x/eval-default.json"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("energy_J"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace comorph::report
