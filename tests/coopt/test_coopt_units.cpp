// Candidate masks, R2 over a segment, and the run config (keys, ranges, --set,
// presets that build on others, the resolved config, the settings' list).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include "coopt/acting.hpp"
#include "coopt/config.hpp"
#include "coopt/config_reference.hpp"
#include "coopt/episode_runner.hpp"
#include "coopt/segment.hpp"
#include "coopt/curriculum.hpp"
#include "coopt/training_state.hpp"
#include "report/run_dir.hpp"
#include "support/test_support.hpp"
#include "task/rewards.hpp"

namespace comorph::coopt {
namespace {

const std::string kCi = std::string(COMORPH_SOURCE_DIR) + "/configs/ci.yaml";

TEST(CandidateMask, FirstChoiceAllowsEveryChainThenOnlyFewerModules) {
  const auto all = candidate_mask(make_chain(kMaxModules));
  ASSERT_EQ(all.size(), static_cast<std::size_t>(kCandidates));
  for (int c = 0; c < kCandidates; ++c) EXPECT_EQ(all[c], 1) << "candidate " << c;
  const auto after6 = candidate_mask(make_chain(6));
  for (int c = 0; c < kCandidates; ++c) EXPECT_EQ(after6[c], modules_of(c) <= 6 ? 1 : 0) << modules_of(c);
  const auto after2 = candidate_mask(make_chain(2));
  EXPECT_EQ(after2[candidate_of(2)], 1);
  for (int m = 3; m <= kMaxModules; ++m) EXPECT_EQ(after2[candidate_of(m)], 0) << m;
  Configuration not_a_candidate = make_chain(3);
  not_a_candidate.C_s[1] = {2, 3, kBackFace, kBackFace, 1};
  EXPECT_THROW(candidate_mask(not_a_candidate), std::invalid_argument);
}

// The DQN's action indices stay what they were when the candidates were counts.
TEST(CandidateMask, ActionIndexIsTheChainLengthMinusTwo) {
  for (int a = 0; a < kCandidates; ++a) {
    EXPECT_EQ(candidates()[a], make_chain(a + 2)) << a;
    EXPECT_EQ(module_count(candidates()[a]), modules_of(a)) << a;
    EXPECT_EQ(candidate_index(candidates()[a]), a);
  }
}

TEST(EpisodePlan, RandomConfigIntervalDrawsEveryKthTrainingEpisodesChainsButNeverTheRefits) {
  TrainerParams t;
  t.warmup_episodes = 4;
  t.episodes = 12;
  t.config_refit_episodes = 6;
  auto random_episodes = [&t] {
    std::vector<int> v;
    for (int e = 0; e < t.total_episodes(); ++e)
      if (plan_episode(t, e).random_config) v.push_back(e);
    return v;
  };
  EXPECT_EQ(random_episodes(), (std::vector<int>{0, 1, 2, 3}));  // the warm-up only
  t.random_config_interval = 5;
  EXPECT_EQ(random_episodes(), (std::vector<int>{0, 1, 2, 3, 5, 10, 15}));  // 16..21 are the refit's
  EXPECT_FALSE(plan_episode(t, 5).scripted);
  EXPECT_FALSE(plan_episode(t, 5).pilot);
}

// trainer.refit_sweep_scenes: the refit's first scenes x 9 episodes come in
// groups of 9 on one scene each, the first configuration forced to each
// candidate in turn; the rest of the refit, and everything before it, plays
// its own scene with the DQN's choice. The forced choice applies to the
// episode's first decision only.
TEST(EpisodePlan, RefitSweepPlaysEachSceneOncePerChainLength) {
  TrainerParams t;
  t.warmup_episodes = 2;
  t.episodes = 3;
  t.config_refit_episodes = 2 * kCandidates + 4;
  t.refit_sweep_scenes = 2;
  const int start = t.refit_start();
  for (int e = 0; e < t.total_episodes(); ++e) {
    const EpisodePlan p = plan_episode(t, e);
    const int into = e - start;
    if (into >= 0 && into < 2 * kCandidates) {
      EXPECT_EQ(p.first_config, into % kCandidates) << e;
      EXPECT_EQ(p.spec.seed, plan_episode(t, start + into / kCandidates * kCandidates).spec.seed) << e;
    } else {
      EXPECT_EQ(p.first_config, -1) << e;
    }
  }
  EXPECT_NE(plan_episode(t, start).spec.seed, plan_episode(t, start + kCandidates).spec.seed);
  EXPECT_NE(plan_episode(t, start + 2 * kCandidates).spec.seed, plan_episode(t, start).spec.seed);
  t.refit_sweep_scenes = 0;
  for (int e = 0; e < t.total_episodes(); ++e) EXPECT_EQ(plan_episode(t, e).first_config, -1);
  EXPECT_NE(plan_episode(t, start + 1).spec.seed, plan_episode(t, start).spec.seed);
}

// trainer.stair_curriculum's draw: uniform until the run fails somewhere,
// then a share in proportion to each height's failure rate over its window.
TEST(StairCurriculum, DrawsHeightsInProportionToTheirRecentFailures) {
  StairCurriculum c({0.04, 0.06, 0.08}, 4);
  for (const double w : c.weights(1.0)) EXPECT_NEAR(w, 1.0 / 3, 1e-12);  // no outcome yet: every height fails
  for (int i = 0; i < 4; ++i) {
    c.record(0.04, true);
    c.record(0.0600000001, true);  // the nearest of the run's heights
    c.record(0.08, i % 2 == 0);
  }
  EXPECT_EQ(c.failure_rates(), (std::vector<double>{0.0, 0.0, 0.5}));
  EXPECT_EQ(c.weights(1.0), (std::vector<double>{0.0, 0.0, 1.0}));
  const std::vector<double> half = c.weights(0.5);
  EXPECT_NEAR(half[0], 1.0 / 6, 1e-12);
  EXPECT_NEAR(half[2], 2.0 / 3, 1e-12);
  for (const double w : c.weights(0.0)) EXPECT_NEAR(w, 1.0 / 3, 1e-12);
  // The window forgets: four later successes at 0.08 m leave no failure anywhere (uniform again).
  for (int i = 0; i < 4; ++i) c.record(0.08, true);
  for (const double w : c.weights(1.0)) EXPECT_NEAR(w, 1.0 / 3, 1e-12);
  c.record(0.06, false);
  EXPECT_EQ(c.height_at(c.weights(1.0), 0.0), 0.06);
  EXPECT_EQ(c.height_at(c.weights(1.0), 0.999), 0.06);

  // Draws from independent streams follow the weights; one stream always draws the same.
  const std::vector<double> w{0.1, 0.3, 0.6};
  int count[3] = {0, 0, 0};
  const int n = 6000;
  for (int e = 0; e < n; ++e) {
    const double h = c.draw(w, stream_seed(1, e, 3));
    EXPECT_EQ(h, c.draw(w, stream_seed(1, e, 3)));
    count[h < 0.05 ? 0 : h < 0.07 ? 1 : 2] += 1;
  }
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(count[i] / static_cast<double>(n), w[static_cast<std::size_t>(i)], 0.025) << i;

  // The checkpoint's text reads back; a malformed one is refused.
  StairCurriculum back({0.04, 0.06, 0.08}, 4);
  back.set_outcomes_text(c.outcomes_text());
  EXPECT_EQ(back.failure_rates(), c.failure_rates());
  EXPECT_EQ(back.outcomes_text(), "1111,1110,1111");
  EXPECT_THROW(back.set_outcomes_text("11,11"), std::runtime_error);
  EXPECT_THROW(back.set_outcomes_text("11,1x,1"), std::runtime_error);
  EXPECT_THROW(back.set_outcomes_text("11111,1,1"), std::runtime_error);
}

// trainer.chain_curriculum's draw: every (height, first chain) pair alike
// until played, then in proportion to p (1 - p) of its recent climbs, with a
// floor where the run always or never climbs.
TEST(ChainCurriculum, DrawsThePairsWhoseClimbIsLeastCertain) {
  ChainCurriculum c({0.04, 0.08}, 2, 4, 4);  // pairs: (0.04, 2), (0.04, 3), (0.04, 4), (0.08, 2), ...
  ASSERT_EQ(c.pairs(), 6u);
  for (const double w : c.weights()) EXPECT_NEAR(w, 1.0 / 6, 1e-12);
  for (int i = 0; i < 4; ++i) {
    c.record(0.04, 2, true);        // always: the floor
    c.record(0.08, 2, false);       // never: the floor
    c.record(0.079, 4, i % 2 == 0);  // half the time (the nearest height): the most
  }
  c.record(0.04, 3, true);  // 1 of 1: certain so far
  EXPECT_EQ(c.climb_rates(), (std::vector<double>{1.0, 1.0, -1.0, 0.0, -1.0, 0.5}));
  // Not played yet counts as half the time.
  const double k = ChainCurriculum::kFloor, total = 2 * k + k + 0.25 + 0.25 + 0.25;
  const std::vector<double> w = c.weights();
  EXPECT_NEAR(w[0], k / total, 1e-12);
  EXPECT_NEAR(w[1], k / total, 1e-12);
  EXPECT_NEAR(w[2], 0.25 / total, 1e-12);
  EXPECT_NEAR(w[3], k / total, 1e-12);
  EXPECT_NEAR(w[5], 0.25 / total, 1e-12);
  const ChainCurriculum::Pair first = c.pair_at(w, 0.0), last = c.pair_at(w, 0.999999);
  EXPECT_EQ(first.height_m, 0.04);
  EXPECT_EQ(first.modules, 2);
  EXPECT_EQ(last.height_m, 0.08);
  EXPECT_EQ(last.modules, 4);
  EXPECT_THROW(c.record(0.04, 5, true), std::invalid_argument);

  // Draws from independent streams follow the weights.
  int drawn[6] = {0, 0, 0, 0, 0, 0};
  const int n = 6000;
  for (int e = 0; e < n; ++e) {
    const ChainCurriculum::Pair p = c.draw(w, stream_seed(1, e, 5));
    drawn[(p.height_m > 0.06 ? 3 : 0) + p.modules - 2] += 1;
  }
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(drawn[i] / static_cast<double>(n), w[static_cast<std::size_t>(i)], 0.025) << i;

  ChainCurriculum back({0.04, 0.08}, 2, 4, 4);
  back.set_outcomes_text(c.outcomes_text());
  EXPECT_EQ(back.climb_rates(), c.climb_rates());
  EXPECT_EQ(back.outcomes_text(), "1111,1,,0000,,1010");
  EXPECT_THROW(back.set_outcomes_text("1111,1,,0000,1010"), std::runtime_error);
}

TEST(Segment, DecisionReturnsSumTheLaterSegmentsDiscountedOncePerDecision) {
  std::vector<float> r2{300.0f, 500.0f, -10.0f};
  to_decision_returns(r2, 0.5);
  EXPECT_FLOAT_EQ(r2[2], -10.0f);
  EXPECT_FLOAT_EQ(r2[1], 500.0f + 0.5f * -10.0f);
  EXPECT_FLOAT_EQ(r2[0], 300.0f + 0.5f * 495.0f);
  std::vector<float> none;
  to_decision_returns(none, 0.99);
  EXPECT_TRUE(none.empty());
}

TEST(Segment, StairSegmentAccumulatesR1AndPaysClimbMinusStairEnergy) {
  task::R2Params p;  // sigma1 1, s_base 0.04, r_s 60, sigma3 0.003
  Segment s;
  s.begin(/*stairs_climbed=*/false, /*E_c so far=*/5.0);
  const double r1[] = {0.5, -0.25, 1.0, 2.0};
  double sum = 0;
  for (int i = 0; i < 4; ++i) {
    s.add_step(r1[i], i == 2);
    sum += r1[i];
  }
  EXPECT_EQ(s.steps(), 4);
  EXPECT_DOUBLE_EQ(s.sum_r1(), sum);
  EXPECT_TRUE(s.climbed());
  // Stair energy counted from the decision on: 125 J - 5 J = 120 J.
  const double expected = sum + (1.0 + 0.08 / 0.04) * 60.0 - 0.003 * 120.0;
  EXPECT_NEAR(s.r2(p, 0.08, 125.0), expected, 1e-12);
  // Not climbed: no r_s, the energy still costs.
  Segment t;
  t.begin(false, 0.0);
  t.add_step(1.0, false);
  EXPECT_NEAR(t.r2(p, 0.06, 100.0), 1.0 - 0.3, 1e-12);
}

TEST(Segment, AfterTheStairsOnlyTheSummedR1Counts) {
  task::R2Params p;
  Segment s;
  s.begin(/*stairs_climbed=*/true, 300.0);
  for (int i = 0; i < 10; ++i) s.add_step(0.1, false);
  EXPECT_EQ(s.steps(), 10);
  EXPECT_FALSE(s.stairs_segment());
  EXPECT_NEAR(s.r2(p, 0.08, 900.0), 1.0, 1e-12);
  s.begin(true, 0.0);  // a new segment starts from zero
  EXPECT_EQ(s.steps(), 0);
  EXPECT_EQ(s.sum_r1(), 0.0);
}

TEST(CooptConfig, CiPresetLoadsAndSetOverridesNestedKeys) {
  const CooptConfig c = load_coopt_config(kCi, {"trainer.episodes=7", "env.task.max_steps=99", "td3.hidden_sizes=[8, 8]",
                                                "perception.switch_detector.interval=30"});
  EXPECT_EQ(c.trainer.episodes, 7);
  EXPECT_EQ(c.env.task.max_steps, 99);
  EXPECT_EQ(c.perception.switch_detector.interval, 30);
  EXPECT_EQ(c.td3.hidden_sizes, (std::vector<int>{8, 8}));
  EXPECT_NE(c.text.find("episodes: 7"), std::string::npos);
  EXPECT_EQ(c.preset, "ci");
  // The resolved text reloads to the same config (what resume relies on).
  EXPECT_EQ(coopt_config_from_text(c.text, "copy").text, c.text);
}

// A run's config holds every setting, defaults included, and only the
// sections the run uses; an input that resolves to the same settings is the
// same run, whatever it spells out.
TEST(CooptConfig, TheResolvedConfigHoldsEveryDefaultAndIsTheRunsIdentity) {
  const CooptConfig c = load_coopt_config(kCi);
  for (const char* key : {"trainer:\n  mode: hierarchical", "  pilot_labels: false", "env:\n  robot:\n    module_length: 0.16",
                          "    stair_height_c: 0.08", "perception:\n  classifier:", "td3:\n  gamma: 0.99",
                          "  actor_q_weight: 1", "dqn:\n", "eval:\n  episodes: 6"})
    EXPECT_NE(c.text.find(key), std::string::npos) << key << "\n" << c.text;
  EXPECT_EQ(c.text.find("sac:"), std::string::npos) << "a td3 run does not use sac:";
  EXPECT_EQ(c.text.find("dqn_refit:"), std::string::npos);
  // Spelling out a default, or a section the run does not use, changes nothing.
  EXPECT_EQ(load_coopt_config(kCi, {"trainer.pilot_labels=false", "sac.gamma=0.5"}).text, c.text);
  EXPECT_NE(load_coopt_config(kCi, {"trainer.pilot_labels=true"}).text, c.text);
  const CooptConfig sac = load_coopt_config(kCi, {"trainer.motion_algo=sac"});
  EXPECT_NE(sac.text.find("sac:\n  gamma:"), std::string::npos);
  EXPECT_EQ(sac.text.find("td3:"), std::string::npos);
  const CooptConfig fixed = load_coopt_config(kCi, {"trainer.mode=fixed"});
  EXPECT_EQ(fixed.text.find("dqn:"), std::string::npos);
}

// `base:` names the preset a file builds on; its keys apply first.
TEST(CooptConfig, APresetBuildsOnItsBase) {
  const std::string dir = test_support::fresh_temp_dir("preset_base");
  std::filesystem::copy_file(kCi, dir + "/ci.yaml");
  std::ofstream(dir + "/longer.yaml") << "base: ci.yaml\ntrainer:\n  episodes: 9  # why: longer\ntd3:\n  hidden_sizes: [16]\n";
  const CooptConfig longer = load_coopt_config(dir + "/longer.yaml");
  EXPECT_EQ(longer.trainer.episodes, 9);
  EXPECT_EQ(longer.td3.hidden_sizes, std::vector<int>{16});
  // The rest is the base's: the same run as the base with those two keys set.
  EXPECT_EQ(longer.text, load_coopt_config(kCi, {"trainer.episodes=9", "td3.hidden_sizes=[16]"}).text);
  EXPECT_EQ(longer.preset, "longer");
  // A fault names the file that has it, with the line.
  std::ofstream(dir + "/bad.yaml") << "base: longer.yaml\ntrainer:\n  episodes: -1\n";
  EXPECT_EQ(test_support::error_of([&] { load_coopt_config(dir + "/bad.yaml"); }),
            dir + "/bad.yaml: field 'trainer.episodes': value -1 out of range [0, 10000000] (line 3)");
  std::ofstream(dir + "/missing.yaml") << "base: nothere.yaml\n";
  EXPECT_NE(test_support::error_of([&] { load_coopt_config(dir + "/missing.yaml"); })
                .find(dir + "/missing.yaml: field 'base': no preset '" + dir + "/nothere.yaml' (line 1)"),
            std::string::npos);
  std::ofstream(dir + "/loop.yaml") << "base: loop.yaml\n";
  EXPECT_NE(test_support::error_of([&] { load_coopt_config(dir + "/loop.yaml"); }).find("more than 8 presets deep"),
            std::string::npos);
  std::filesystem::remove_all(dir);
}

// configs/rl-only-curricula.yaml is the recipe docs/results.md measured
// ("Three seeds of the chain curriculum"): rl-only.yaml with these settings,
// nothing more; and it stays RL alone (no pilot acts or labels).
TEST(CooptConfig, TheRlOnlyCurriculaPresetIsTheMeasuredRecipe) {
  const std::string configs = std::string(COMORPH_SOURCE_DIR) + "/configs/";
  const CooptConfig preset = load_coopt_config(configs + "rl-only-curricula.yaml");
  const CooptConfig measured = load_coopt_config(
      configs + "rl-only.yaml",
      {"trainer.stair_curriculum=0.5", "trainer.config_energy_weight=0.02", "trainer.chain_curriculum=0.5",
       "trainer.decision_image_first_only=true", "dqn_refit.reward_scale=0.01", "dqn_refit.learning_rate=1e-3",
       "dqn_refit.weight_decay=0.5"});
  EXPECT_EQ(preset.text, measured.text);
  EXPECT_EQ(preset.preset, "rl-only-curricula");
  EXPECT_FALSE(preset.trainer.pilot_labels);
  EXPECT_EQ(preset.trainer.scripted_interval, 0);
  EXPECT_EQ(preset.td3.bc_weight, 0);
}

// An empty file is refused as empty (not as a file without a td3: section);
// a key that is a list names the file and the line.
TEST(CooptConfig, AnEmptyFileOrAListKeyIsRefusedAsSuch) {
  EXPECT_EQ(test_support::error_of([] { coopt_config_from_text("", "empty.yaml"); }).rfind("empty.yaml: empty config", 0),
            0u);
  EXPECT_EQ(test_support::error_of([] { coopt_config_from_text("# only a comment\n", "c.yaml"); }).rfind("c.yaml: empty config", 0),
            0u);
  EXPECT_EQ(test_support::error_of([] { coopt_config_from_text("trainer:\n  [episodes]: 3\n", "l.yaml"); }),
            "l.yaml: line 2: a key must be a name, not a list");
  EXPECT_EQ(test_support::error_of([] { coopt_config_from_text("trainer:\n  - episodes: 3\n", "s.yaml"); }),
            "s.yaml: field 'trainer': expected a mapping (line 2)");
}

// `comorph config keys` lists every key of every section with its default,
// type and range, and meaning; with a preset, its values and what differs.
TEST(ConfigReference, KeysListEveryFieldWithDefaultRangeAndMeaning) {
  const std::string all = config_keys_text();
  for (const char* line : {"trainer: The hierarchical trainer", "  trainer.episodes ", "4000",
                           "integer in [0, 10000000]", "training episodes after the warm-up", "env.robot.wheel_radius",
                           "td3.actor_q_weight", "sac.alpha", "dqn.discount_per", "step | decision", "eval.workers",
                           "perception.switch_detector.agreement"})
    EXPECT_NE(all.find(line), std::string::npos) << line;
  const CooptConfig ci = load_coopt_config(kCi);
  const std::string preset = config_keys_text(&ci);
  // ci sets 4 training episodes (default 4000) and keeps the default mode.
  EXPECT_NE(preset.find("* trainer.episodes "), std::string::npos) << preset.substr(0, 2000);
  EXPECT_NE(preset.find("  trainer.mode "), std::string::npos);
  EXPECT_EQ(preset.find("* trainer.mode "), std::string::npos);
}

// A run's configuration for grouping seeds: a config.yaml written as the merged
// input (runs made before configs were resolved) and one written resolved are
// the same configuration when their settings are; the seed does not count, a
// changed setting does.
TEST(ConfigIdentity, MergedAndResolvedFilesOfTheSameSettingsAreOneConfiguration) {
  const auto dir = std::filesystem::temp_directory_path() / ("comorph_identity_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream((dir / name).string()) << text;
    return (dir / name).string();
  };
  std::string merged_text = test_support::read_text(kCi);
  const auto seed_line = merged_text.find("  seed: 1\n");
  ASSERT_NE(seed_line, std::string::npos);
  merged_text.replace(seed_line, 10, "  seed: 3\n");
  const std::string merged = write("merged.yaml", merged_text);
  const std::string resolved = write("resolved.yaml", load_coopt_config(kCi, {"trainer.seed=1"}).text);
  const std::string other = write("other.yaml", load_coopt_config(kCi, {"td3.batch_size=16"}).text);
  EXPECT_NE(report::config_as_written(merged), report::config_as_written(resolved));
  EXPECT_EQ(config_identity(merged), config_identity(resolved));
  EXPECT_NE(config_identity(other), config_identity(resolved));
  EXPECT_FALSE(YAML::Load(config_identity(resolved))["trainer"]["seed"]);
  std::filesystem::remove_all(dir);
}

// docs/config.md is the generated list; regenerate it when this fails.
TEST(ConfigReference, DocsConfigMdIsInStepWithTheCode) {
  const std::string page = std::string(COMORPH_SOURCE_DIR) + "/docs/config.md";
  EXPECT_EQ(test_support::read_text(page), config_reference_markdown())
      << "docs/config.md is out of date: build/apps/comorph config keys --markdown > docs/config.md";
}

void expect_error(const std::vector<std::string>& sets, const std::string& needle) {
  try {
    load_coopt_config(kCi, sets);
    ADD_FAILURE() << "no error for " << sets.front();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(CooptConfig, UnknownKeysAndOutOfRangeValuesNameTheKey) {
  expect_error({"trainer.episodez=3"}, "trainer.episodez");
  expect_error({"trainer.fixed_modules=11"}, "trainer.fixed_modules");
  expect_error({"trainer.sync_interval=0"}, "trainer.sync_interval");
  expect_error({"trainer.motion_algo=ppo"}, "trainer.motion_algo");
  expect_error({"trainer.scene_source=classifier"}, "trainer.classifier_dir");
  expect_error({"td3.learning_rat=1"}, "learning_rat");
  expect_error({"dqn.batch_size=abc"}, "batch_size");
  expect_error({"env.task.max_steps=0"}, "max_steps");
  expect_error({"env.robot.wheel_radiuss=1"}, "wheel_radiuss");
  expect_error({"perception.switch_detector.agreement=1.5"}, "agreement");
  expect_error({"td3.random_action_episodes=5"}, "warmup_episodes");
  expect_error({"nosection.x=1"}, "nosection");
  expect_error({"trainer.episodes"}, "key=value");
  expect_error({"trainer.config_target_distance=true", "trainer.config_vector=false"}, "trainer.config_target_distance");
}

// trainer.config_target_distance: the DQN's vector gains the distance to the target, in units of 10 m.
TEST(ConfigVector, TargetDistanceFollowsTheChainLengthAndTheScene) {
  const CooptConfig plain = load_coopt_config(kCi);
  const CooptConfig with = load_coopt_config(kCi, {"trainer.config_target_distance=true"});
  ASSERT_EQ(config_spec(with).vector_size, config_spec(plain).vector_size + 1);
  rl::Observation o;
  rl::allocate(config_spec(with), o);
  std::vector<std::uint8_t> mask;
  fill_config_vector(with.trainer, make_chain(6), 1, 4.2, mask, o);
  EXPECT_FLOAT_EQ(o.vector[0], 0.6f);  // C_n / 10
  EXPECT_FLOAT_EQ(o.vector[2], 1.0f);  // scene 1
  EXPECT_FLOAT_EQ(o.vector.back(), 0.42f);
  EXPECT_THROW(fill_config_vector(with.trainer, make_chain(6), 1, -1.0, mask, o), std::invalid_argument);
  rl::allocate(config_spec(plain), o);
  fill_config_vector(plain.trainer, make_chain(6), 1, -1.0, mask, o);  // not asked for: not needed
  EXPECT_EQ(o.vector.size(), 4u);
}

// trainer.decision_image_first_only: the first decision sees the decision
// camera, every later one a blank image beside the same vector; without it
// the later decisions see the camera too. An image without the vector is refused.
TEST(ConfigVector, DecisionImageFirstOnlyBlanksTheLaterDecisionsImage) {
  const auto image_sum = [](bool first_only, bool first) {
    const CooptConfig c = load_coopt_config(
        kCi, {"trainer.decision_camera=true", std::string("trainer.decision_image_first_only=") + (first_only ? "true" : "false")});
    task::MultiTaskEnv env(c.env);
    task::EpisodeSpec spec = eval_spec(c, task::scenario_named("default"), 5150, 2);
    spec.configuration = make_chain(6);
    env.reset(spec);
    rl::Observation o;
    rl::allocate(config_spec(c), o);
    std::fill(o.image.begin(), o.image.end(), 0.5f);  // what a previous decision left
    std::vector<std::uint8_t> mask;
    fill_config(env, c.trainer, 1, first, mask, o);
    EXPECT_FLOAT_EQ(o.vector[0], 0.6f);  // C_n / 10 in every case
    EXPECT_FLOAT_EQ(o.vector[2], 1.0f);  // scene 1
    double sum = 0;
    for (float v : o.image) sum += std::abs(v);
    return sum;
  };
  const double first = image_sum(true, true);
  EXPECT_GT(first, 0.0);
  EXPECT_EQ(image_sum(true, false), 0.0);
  EXPECT_DOUBLE_EQ(image_sum(false, false), first);  // the same env, the same camera
  expect_error({"trainer.decision_image_first_only=true", "trainer.config_vector=false"},
               "trainer.decision_image_first_only");
}

// dqn_refit: holds only the keys in which the refit DQN differs from dqn:.
TEST(CooptConfig, DqnRefitOverlaysTheDqnSection) {
  const CooptConfig plain = load_coopt_config(kCi, {"trainer.config_refit_episodes=2"});
  EXPECT_EQ(plain.dqn_refit.loss, plain.dqn.loss);
  EXPECT_EQ(plain.dqn_refit.batch_size, plain.dqn.batch_size);
  const CooptConfig c = load_coopt_config(
      kCi, {"trainer.config_refit_episodes=2", "dqn.loss=huber", "dqn_refit.loss=mse", "dqn_refit.batch_size=7"});
  EXPECT_EQ(c.dqn.loss, rl::DqnLoss::huber);
  EXPECT_EQ(c.dqn_refit.loss, rl::DqnLoss::mse);
  EXPECT_EQ(c.dqn_refit.batch_size, 7);
  EXPECT_NE(c.dqn.batch_size, 7);
  EXPECT_EQ(c.dqn_refit.learning_rate, c.dqn.learning_rate);  // the rest is dqn:'s
  EXPECT_EQ(c.dqn_refit.hidden_sizes, c.dqn.hidden_sizes);
  EXPECT_NE(c.text.find("dqn_refit"), std::string::npos);
  // The model that learns, and the returns it learns (trainer.config_target: return), take the refit's gamma.
  const CooptConfig myopic = load_coopt_config(kCi, {"trainer.config_refit_episodes=2", "dqn_refit.gamma=0"});
  EXPECT_EQ(config_model_params(myopic, true).gamma, 0.0);
  EXPECT_EQ(config_model_params(myopic, false).gamma, myopic.dqn.gamma);
  EXPECT_GT(myopic.dqn.gamma, 0.0);
  // Where nothing is refitted it is no part of the run's identity: a preset's
  // fixed columns are the same runs with and without it.
  for (const char* no_refit : {"trainer.config_refit_episodes=0", "trainer.mode=fixed"})
    EXPECT_EQ(load_coopt_config(kCi, {no_refit, "dqn_refit.loss=mse"}).text, load_coopt_config(kCi, {no_refit}).text)
        << no_refit;
  expect_error({"trainer.config_refit_episodes=2", "dqn_refit.los=mse"}, "dqn_refit (over dqn)");
  // The refit DQN may have its own architecture (evaluation loads the one a checkpoint holds).
  const CooptConfig own = load_coopt_config(kCi, {"trainer.config_refit_episodes=2", "dqn_refit.hidden_sizes=[9]",
                                                  "dqn_refit.ensemble_size=3"});
  EXPECT_EQ(own.dqn_refit.hidden_sizes, std::vector<int>{9});
  EXPECT_EQ(own.dqn_refit.ensemble_size, 3);
  EXPECT_EQ(own.dqn.hidden_sizes, plain.dqn.hidden_sizes);
  EXPECT_EQ(own.dqn.ensemble_size, 1);
}

TEST(Scenario, NamesMapToObstaclesAndVariant) {
  EXPECT_EQ(task::scenario_named("default").obstacles, -1);
  EXPECT_EQ(task::scenario_named("default").variant, sim::Variant::standard);
  EXPECT_EQ(task::scenario_named("obstacles8").obstacles, 8);
  EXPECT_EQ(task::scenario_named("mixed").variant, sim::Variant::mixed);
  EXPECT_THROW(task::scenario_named("stairs9"), std::runtime_error);
  // The config reads the same names.
  EXPECT_EQ(load_coopt_config(kCi, {"trainer.scenario=obstacles7"}).trainer.scenario, task::Scenario::obstacles7);
  expect_error({"trainer.scenario=stairs9"}, "'stairs9' is not one of default | obstacles7 | obstacles8 | mixed");
}

}  // namespace
}  // namespace comorph::coopt
