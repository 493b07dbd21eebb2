// Short runs of the ci preset: the hierarchy end to end, scene switches and the
// configuration model's semi-MDP transitions, checkpoints and resume (same
// results as an uninterrupted run), thread-independence, baselines, the
// evaluator, the CLI's bad-input handling, and a learning test.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <set>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "coopt/acting.hpp"
#include "coopt/config.hpp"
#include "coopt/episode_runner.hpp"
#include "coopt/segment.hpp"
#include "coopt/curriculum.hpp"
#include "coopt/trainer.hpp"
#include "coopt/training_state.hpp"
#include "perception/params.hpp"
#include "perception/scene_classifier.hpp"
#include "support/test_support.hpp"

namespace comorph::coopt {
namespace {
namespace fs = std::filesystem;

const std::string kCi = std::string(COMORPH_SOURCE_DIR) + "/configs/ci.yaml";

std::string temp_dir(const std::string& name) { return test_support::fresh_temp_dir("coopt_" + name); }

// A log line with every field that a change of behaviour would move.
std::string line_of(const EpisodeLog& l) {
  std::ostringstream s;
  s.precision(17);
  s << l.episode << ' ' << l.seed << ' ' << l.stair_height_m << ' ' << l.success << ' ' << l.termination << ' '
    << l.time_s << ' ' << l.energy_J << ' ' << l.distance_fraction << ' ' << l.return_R1 << ' ' << l.return_R2
    << ' ' << l.steps << ' ' << l.switches << ' ';
  for (int m : l.configurations) s << m << ';';
  return s.str();
}

struct RunResult {
  std::vector<std::string> episodes;
  std::vector<EpisodeLog> logs;
  std::vector<DecisionLog> decisions;
  int evaluations = 0;
  std::vector<EvaluationLog> evaluation_logs;
};

TrainerCallbacks collecting(RunResult& r) {
  TrainerCallbacks cb;
  cb.on_episode = [&r](const EpisodeLog& l) {
    r.episodes.push_back(line_of(l));
    r.logs.push_back(l);
  };
  cb.on_evaluation = [&r](const EvaluationLog& e) {
    r.evaluations += 1;
    r.evaluation_logs.push_back(e);
  };
  cb.on_decision = [&r](const DecisionLog& d) { r.decisions.push_back(d); };
  return cb;
}

// A run in `dir` interrupted (Ctrl-C) after episode index `last` ends:
// that episode is finished and checkpointed (with simulation threads, the
// block holding it: `done` episodes). Its rows go to `part`.
void run_until_stopped(const CooptConfig& c, const std::string& dir, int last, RunResult& part, int done = -1) {
  std::atomic<bool> stop{false};
  TrainerCallbacks cb = collecting(part);
  auto inner = cb.on_episode;
  cb.on_episode = [&stop, last, inner](const EpisodeLog& l) {
    inner(l);
    if (l.episode == last) stop = true;
  };
  Trainer t(c, dir, cb);
  EXPECT_FALSE(t.run(&stop));
  EXPECT_EQ(t.episodes_done(), done < 0 ? last + 1 : done);
}

// The run in `dir` resumed (after `done` episodes) and killed (kill -9)
// right after episode index `last` is written, before its checkpoint.
void resume_until_killed(const CooptConfig& c, const std::string& dir, int done, int last, RunResult& part) {
  TrainerCallbacks cb = collecting(part);
  auto inner = cb.on_episode;
  cb.on_episode = [inner, last](const EpisodeLog& l) {
    inner(l);
    if (l.episode == last) throw std::runtime_error("killed");
  };
  Trainer t(c, dir, cb);
  t.resume();
  EXPECT_EQ(t.episodes_done(), done);
  EXPECT_THROW(t.run(), std::runtime_error);
}

// A run in `dir` interrupted after episode index `last` ends, then resumed
// to its end: every episode's row, in order.
RunResult run_stopped_and_resumed(const CooptConfig& c, const std::string& dir, int last) {
  RunResult r;
  run_until_stopped(c, dir, last, r);
  Trainer t(c, dir, collecting(r));
  t.resume();
  EXPECT_TRUE(t.run());
  return r;
}

// `sets` and one more.
std::vector<std::string> with(std::vector<std::string> sets, const std::string& more) {
  sets.push_back(more);
  return sets;
}

RunResult run_ci(const std::vector<std::string>& sets, const std::string& dir) {
  RunResult r;
  Trainer t(load_coopt_config(kCi, sets), dir, collecting(r));
  EXPECT_TRUE(t.run());
  return r;
}

TEST(Trainer, CiPresetCompletesAndWritesALoadableCheckpoint) {
  const std::string dir = temp_dir("ci");
  const CooptConfig c = load_coopt_config(kCi);
  RunResult r;
  {
    Trainer t(c, dir, collecting(r));
    ASSERT_TRUE(t.run());
    EXPECT_EQ(t.episodes_done(), c.trainer.warmup_episodes + c.trainer.episodes);
    EXPECT_GT(t.env_steps(), 0);
  }
  ASSERT_EQ(r.logs.size(), static_cast<std::size_t>(c.trainer.warmup_episodes + c.trainer.episodes));
  // eval_interval 3 over 6 episodes: after 3 and after 6.
  EXPECT_EQ(r.evaluations, 2);
  for (const auto& l : r.logs) {
    EXPECT_GE(l.modules_total, kMinModules);
    EXPECT_LE(l.modules_total, kMaxModules);
    EXPECT_GT(l.steps, 0);
    EXPECT_LE(l.steps, c.env.task.max_steps);
    EXPECT_FALSE(l.termination.empty());
  }
  EXPECT_TRUE(r.logs[0].warmup);
  EXPECT_FALSE(r.logs.back().warmup);
  const CheckpointInfo info = read_checkpoint_info(dir);
  EXPECT_EQ(info.episodes, 6);
  EXPECT_EQ(info.evaluations, 2);
  EXPECT_EQ(info.config_text, c.text);
  for (const char* f : {"motion.pt", "motion_actor.pt", "config_model.pt", "trainer.yaml"})
    EXPECT_TRUE(fs::exists(fs::path(dir) / "checkpoint" / f)) << f;
  // Loadable: a new trainer restores it and has nothing left to do.
  Trainer again(c, dir);
  again.resume();
  EXPECT_EQ(again.episodes_done(), 6);
  EXPECT_EQ(again.env_steps(), info.env_steps);
  EXPECT_TRUE(again.run());
  EXPECT_EQ(again.episodes_done(), 6);
  fs::remove_all(dir);
}

TEST(Trainer, ResultsDoNotDependOnTheLearnerThread) {
  const std::string a = temp_dir("thr_a"), b = temp_dir("thr_b");
  const RunResult threaded = run_ci({"trainer.learner_thread=true"}, a);
  const RunResult inline_ = run_ci({"trainer.learner_thread=false"}, b);
  EXPECT_EQ(threaded.episodes, inline_.episodes);
  fs::remove_all(a);
  fs::remove_all(b);
}

// The quick preset's additions (demonstrations, clearance row, scaled state,
// decision camera) keep the schedule a function of the step count.
const std::vector<std::string> kWithDemonstrations{
    "trainer.warmup_policy=scripted", "trainer.scripted_interval=2", "trainer.motion_clearance=true",
    "trainer.normalize_state=true",   "trainer.decision_camera=true",  "trainer.pilot_labels=true",
    "td3.bc_weight=1.0"};

TEST(Trainer, ResultsWithDemonstrationsDoNotDependOnTheLearnerThread) {
  const std::string a = temp_dir("demo_thr_a"), b = temp_dir("demo_thr_b");
  std::vector<std::string> threaded = kWithDemonstrations, inline_ = kWithDemonstrations;
  threaded.push_back("trainer.learner_thread=true");
  inline_.push_back("trainer.learner_thread=false");
  EXPECT_EQ(run_ci(threaded, a).episodes, run_ci(inline_, b).episodes);
  fs::remove_all(a);
  fs::remove_all(b);
}

// The scripted pilot drives the warm-up: it climbs straight at the stairs (in
// ci's 120 steps it gets most of the way to the first riser and beyond), where
// uniform random actions go nowhere in particular.
TEST(Trainer, ScriptedWarmupDrivesTowardsTheGoal) {
  const std::string a = temp_dir("warm_scripted"), b = temp_dir("warm_random");
  std::vector<std::string> scripted = kWithDemonstrations;
  scripted.push_back("trainer.warmup_episodes=4");
  const RunResult pilot = run_ci(scripted, a);
  const RunResult random = run_ci({"trainer.warmup_episodes=4"}, b);
  double pilot_d = 0, random_d = 0;
  for (int e = 0; e < 4; ++e) {
    EXPECT_TRUE(pilot.logs[e].warmup);
    pilot_d += pilot.logs[e].distance_fraction / 4;
    random_d += random.logs[e].distance_fraction / 4;
  }
  std::printf("warm-up distance fraction: scripted %.3f, random %.3f\n", pilot_d, random_d);
  EXPECT_GT(pilot_d, random_d + 0.03);
  fs::remove_all(a);
  fs::remove_all(b);
}

// trainer.config_target: return stores each episode's decisions at its end;
// the run completes, reports every decision and leaves an evaluable policy.
// An unknown target is refused with its key.
TEST(Trainer, ConfigModelLearnsFromEpisodeReturns) {
  const std::string dir = temp_dir("dqn_return");
  const RunResult r = run_ci({"trainer.config_target=return"}, dir);
  ASSERT_EQ(r.logs.size(), 6u);
  EXPECT_FALSE(r.decisions.empty());
  EXPECT_TRUE(r.decisions.back().terminated || r.decisions.back().truncated);
  const CooptConfig c = load_coopt_config(kCi, {"trainer.config_target=return"});
  EvalRequest three;
  three.episodes = 3;
  three.seed = 4242;
  three.workers = 1;
  EXPECT_EQ(evaluate(c, dir, three).size(), 3u);
  fs::remove_all(dir);
  try {
    load_coopt_config(kCi, {"trainer.config_target=td"});
    FAIL() << "an unknown trainer.config_target was accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("trainer.config_target"), std::string::npos) << e.what();
  }
}

// trainer.config_learns_from: the DQN stores (and reports) the decisions of
// every episode (all), of those the motion model drove (model: not the 2
// warm-up episodes, nor every 2nd), or of those it drove greedily (greedy,
// every 4th: episode 5). trainer.greedy_motion_interval alone changes that
// episode (no exploration noise) and none before it.
TEST(Trainer, ConfigModelLearnsFromTheChosenEpisodes) {
  const auto run = [](const std::string& from, int greedy_interval, const std::string& name) {
    std::vector<std::string> sets = kWithDemonstrations;
    sets.push_back("trainer.config_learns_from=" + from);
    sets.push_back("trainer.greedy_motion_interval=" + std::to_string(greedy_interval));
    const std::string dir = temp_dir(name);
    RunResult r = run_ci(sets, dir);
    fs::remove_all(dir);
    return r;
  };
  const auto episodes_with_decisions = [](const RunResult& r) {
    std::vector<int> e;
    for (const auto& d : r.decisions)
      if (e.empty() || e.back() != d.episode) e.push_back(d.episode);
    return e;
  };
  const RunResult all = run("all", 0, "dqn_all"), model = run("model", 0, "dqn_model");
  const RunResult greedy = run("greedy", 4, "dqn_greedy"), model_greedy5 = run("model", 4, "dqn_model_greedy");
  EXPECT_EQ(episodes_with_decisions(all), (std::vector<int>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(episodes_with_decisions(model), (std::vector<int>{3, 5}));
  EXPECT_EQ(episodes_with_decisions(greedy), (std::vector<int>{5}));
  ASSERT_EQ(model_greedy5.episodes.size(), 6u);
  ASSERT_EQ(model.episodes.size(), 6u);
  for (int e = 0; e < 5; ++e) EXPECT_EQ(model_greedy5.episodes[e], model.episodes[e]) << "episode " << e;
  EXPECT_NE(model_greedy5.episodes[5], model.episodes[5]);
}

// trainer.config_refit_episodes: the training episodes are those of a run
// without it; then a fresh DQN learns from every decision of the refit
// episodes while the motion model stays as it was (driving a fixed chain, both
// runs' motion models give the same episodes, and their DQNs different ones);
// interrupted inside the refit, the resumed run gives the same episodes.
TEST(Trainer, ConfigRefitTrainsAFreshDqnOnTheFrozenMotionModel) {
  std::vector<std::string> sets = kWithDemonstrations;
  const std::string plain_dir = temp_dir("refit_plain"), refit_dir = temp_dir("refit");
  const RunResult plain = run_ci(sets, plain_dir);
  sets.push_back("trainer.config_refit_episodes=3");
  const RunResult refit = run_ci(sets, refit_dir);
  ASSERT_EQ(plain.episodes.size(), 6u);
  ASSERT_EQ(refit.episodes.size(), 9u);
  for (int e = 0; e < 6; ++e) EXPECT_EQ(refit.episodes[e], plain.episodes[e]) << "episode " << e;
  std::vector<int> refit_decisions;
  for (const auto& d : refit.decisions)
    if (d.episode >= 6 && (refit_decisions.empty() || refit_decisions.back() != d.episode))
      refit_decisions.push_back(d.episode);
  EXPECT_EQ(refit_decisions, (std::vector<int>{6, 7, 8}));
  const auto greedy_lines = [](CooptConfig c, const std::string& dir) {
    std::vector<std::string> lines;
    EvalRequest six;
    six.episodes = 6;
    six.seed = 4242;
    six.workers = 1;
    for (const EpisodeLog& l : evaluate(c, dir, six)) lines.push_back(line_of(l));
    return lines;
  };
  CooptConfig plain_config = load_coopt_config(kCi, kWithDemonstrations);
  CooptConfig refit_config = load_coopt_config(kCi, sets);
  EXPECT_NE(greedy_lines(plain_config, plain_dir), greedy_lines(refit_config, refit_dir));
  plain_config.trainer.mode = refit_config.trainer.mode = TrainerMode::fixed;  // the motion model alone
  EXPECT_EQ(greedy_lines(plain_config, plain_dir), greedy_lines(refit_config, refit_dir));

  // The refit DQN's own hyperparameters (dqn_refit:, its architecture too)
  // train it, evaluation loads it, and a run resumed inside the refit rebuilds
  // it with them: its final DQN is the uninterrupted run's, byte for byte.
  sets.insert(sets.end(), {"dqn_refit.loss=mse", "dqn_refit.learning_rate=0.01", "dqn_refit.learning_starts=1",
                           "dqn_refit.batch_size=2", "dqn_refit.ensemble_size=2"});
  const std::string own_dir = temp_dir("refit_own");
  const RunResult own = run_ci(sets, own_dir);
  EXPECT_EQ(greedy_lines(load_coopt_config(kCi, sets), own_dir).size(), 6u);
  const auto final_dqn = [](const std::string& dir) { return test_support::read_text(dir + "/checkpoint/config_model.pt"); };
  EXPECT_TRUE(final_dqn(own_dir) != final_dqn(refit_dir));  // (no dump of the files)
  const std::string dir = temp_dir("refit_resume");
  const CooptConfig c = load_coopt_config(kCi, sets);
  RunResult resumed;
  run_until_stopped(c, dir, 6, resumed);  // stopped after the first refit episode
  {
    Trainer t(c, dir, collecting(resumed));
    t.resume();
    EXPECT_TRUE(t.run());
  }
  EXPECT_EQ(resumed.episodes, own.episodes);
  EXPECT_TRUE(final_dqn(dir) == final_dqn(own_dir));
  fs::remove_all(plain_dir);
  fs::remove_all(refit_dir);
  fs::remove_all(own_dir);
  fs::remove_all(dir);
}

// trainer.refit_sweep_scenes: the refit's first 9 episodes play one scene
// (seed and stair height) with the first chain forced to 2, 3, ..., 10
// modules in turn; the DQN learns from those decisions as from any refit
// decision; the refit's later episodes play their own scenes.
TEST(Trainer, RefitSweepPlaysOneSceneWithEveryChainLengthFirst) {
  std::vector<std::string> sets = kWithDemonstrations;
  sets.insert(sets.end(), {"trainer.config_refit_episodes=" + std::to_string(kCandidates + 1),
                           "trainer.refit_sweep_scenes=1"});
  const std::string dir = temp_dir("refit_sweep");
  const RunResult r = run_ci(sets, dir);
  const int start = load_coopt_config(kCi, sets).trainer.refit_start();
  ASSERT_EQ(static_cast<int>(r.logs.size()), start + kCandidates + 1);
  for (int a = 0; a < kCandidates; ++a) {
    const EpisodeLog& l = r.logs[static_cast<std::size_t>(start + a)];
    ASSERT_FALSE(l.configurations.empty());
    EXPECT_EQ(l.configurations.front(), modules_of(a)) << "refit episode " << a;
    EXPECT_EQ(l.seed, r.logs[static_cast<std::size_t>(start)].seed);
    EXPECT_EQ(l.stair_height_m, r.logs[static_cast<std::size_t>(start)].stair_height_m);
  }
  EXPECT_NE(r.logs.back().seed, r.logs[static_cast<std::size_t>(start)].seed);
  int refit_decisions = 0;
  for (const DecisionLog& d : r.decisions) refit_decisions += d.episode >= start;
  EXPECT_GE(refit_decisions, kCandidates);
  EXPECT_THROW(load_coopt_config(kCi, {"trainer.config_refit_episodes=8", "trainer.refit_sweep_scenes=1"}),
               std::runtime_error);
  fs::remove_all(dir);
}

TEST(Trainer, ResumeAfterInterruptionContinuesTheSameEpisodesWithIdenticalResults) {
  const std::vector<std::string> sets{"trainer.episodes=6", "trainer.checkpoint_interval=3"};
  // The data rows of the episodes.csv the trainer writes (RunStore).
  auto csv_rows = [](const std::string& run_dir) {
    std::ifstream in(run_dir + "/episodes.csv");
    std::vector<std::string> rows;
    std::string line;
    std::getline(in, line);  // the header
    while (std::getline(in, line)) rows.push_back(line);
    return rows;
  };
  const std::string full_dir = temp_dir("full");
  const RunResult full = run_ci(sets, full_dir);
  ASSERT_EQ(full.episodes.size(), 8u);
  ASSERT_EQ(csv_rows(full_dir).size(), 8u);

  // Ctrl-C during episode 3 (index 2): it is finished and checkpointed.
  const std::string dir = temp_dir("resume");
  const CooptConfig c = load_coopt_config(kCi, sets);
  RunResult part;
  run_until_stopped(c, dir, 4, part);
  // kill -9 after episode 7 was logged but before its checkpoint (every 3):
  // the CSV has a row the checkpoint does not count.
  resume_until_killed(c, dir, 5, 6, part);
  EXPECT_EQ(read_checkpoint_info(dir).episodes, 6);
  EXPECT_EQ(csv_rows(dir).size(), 7u);
  RunResult rest;
  {
    Trainer t(c, dir, collecting(rest));
    t.resume();  // truncates episodes.csv to the 6 rows the checkpoint counted
    EXPECT_EQ(t.episodes_done(), 6);
    EXPECT_TRUE(t.run());
    EXPECT_EQ(t.episodes_done(), 8);
  }
  // No lost and no duplicated episode; identical to the uninterrupted run.
  ASSERT_EQ(rest.episodes.size(), 2u);
  EXPECT_EQ(rest.episodes[1], full.episodes[7]);
  EXPECT_EQ(csv_rows(dir), csv_rows(full_dir));
  fs::remove_all(full_dir);
  fs::remove_all(dir);
}

// trainer.stair_curriculum: each training episode after the warm-up takes
// the height its own stream draws from the run's failure rates so far; the
// warm-up and the refit keep the scene's draw; the outcomes the draws read
// go into the checkpoint, so an interrupted run resumes to the same episodes,
// and several simulation threads repeat their results.
TEST(Trainer, StairCurriculumDrawsTrainingHeightsFromTheRunsOutcomesAndResumesToThem) {
  const std::vector<std::string> base{"trainer.episodes=6", "trainer.checkpoint_interval=3",
                                      "trainer.config_refit_episodes=2"};
  std::vector<std::string> sets = with(base, "trainer.stair_curriculum=1");
  const std::string plain_dir = temp_dir("curriculum_plain"), full_dir = temp_dir("curriculum_full");
  const RunResult plain = run_ci(base, plain_dir);
  const RunResult full = run_ci(sets, full_dir);
  const CooptConfig c = load_coopt_config(kCi, sets);
  const TrainerParams& t = c.trainer;
  ASSERT_EQ(full.logs.size(), 10u);
  StairCurriculum replay(stair_heights(c), t.stair_curriculum_window);  // one actor: the weights after every episode
  int moved = 0;
  for (int e = 0; e < 10; ++e) {
    const EpisodeLog& l = full.logs[static_cast<std::size_t>(e)];
    const double scene_height = plain.logs[static_cast<std::size_t>(e)].stair_height_m;
    if (e < t.warmup_episodes || e >= t.refit_start()) {
      EXPECT_EQ(l.stair_height_m, scene_height) << "episode " << e;
      continue;
    }
    EXPECT_EQ(l.stair_height_m, replay.draw(replay.weights(1.0), stream_seed(t.seed, e, 3))) << "episode " << e;
    moved += l.stair_height_m != scene_height;
    replay.record(l.stair_height_m, l.success);
  }
  EXPECT_GT(moved, 0) << "the curriculum's draws are the scene's own";
  const YAML::Node checkpoint = YAML::LoadFile(full_dir + "/checkpoint/trainer.yaml");
  EXPECT_EQ(checkpoint["stair_curriculum"].as<std::string>(), replay.outcomes_text());

  // Interrupted after episode index 4 and resumed: the same episodes.
  const std::string dir = temp_dir("curriculum_resume");
  RunResult part;
  run_until_stopped(c, dir, 4, part);
  RunResult rest;
  {
    Trainer trainer(c, dir, collecting(rest));
    trainer.resume();
    EXPECT_TRUE(trainer.run());
  }
  ASSERT_EQ(rest.episodes.size(), 5u);
  for (std::size_t i = 0; i < 5; ++i) EXPECT_EQ(rest.episodes[i], full.episodes[i + 5]) << i;

  // Two simulation threads: the weights are the block's, the same with or without the learner thread.
  sets.push_back("trainer.simulation_threads=2");
  const std::string threads_a = temp_dir("curriculum_threads_a"), threads_b = temp_dir("curriculum_threads_b");
  const RunResult a = run_ci(with(sets, "trainer.learner_thread=true"), threads_a);
  const RunResult b = run_ci(with(sets, "trainer.learner_thread=false"), threads_b);
  EXPECT_EQ(a.episodes, b.episodes);

  EXPECT_THROW(load_coopt_config(kCi, {"trainer.stair_curriculum=0.5", "trainer.stair_height=0.06"}),
               std::runtime_error);
  for (const std::string& d : {plain_dir, full_dir, dir, threads_a, threads_b}) fs::remove_all(d);
}

// trainer.chain_curriculum: every training episode after the warm-up plays
// the (height, first chain) pair its own streams draw from the run's climbs
// so far; later decisions stay the DQN's; the warm-up and the refit are
// untouched; the outcomes go into the checkpoint.
TEST(Trainer, ChainCurriculumDrawsTheFirstChainAndHeightFromTheRunsClimbs) {
  const std::vector<std::string> sets{"trainer.episodes=6", "trainer.checkpoint_interval=3",
                                      "trainer.config_refit_episodes=2", "trainer.chain_curriculum=1"};
  const std::string dir = temp_dir("chain_curriculum");
  const RunResult run = run_ci(sets, dir);
  const CooptConfig c = load_coopt_config(kCi, sets);
  const TrainerParams& t = c.trainer;
  ASSERT_EQ(run.logs.size(), 10u);
  ChainCurriculum replay(stair_heights(c), kMinModules, kMaxModules, t.chain_curriculum_window);
  std::set<int> firsts;
  for (int e = t.warmup_episodes; e < t.refit_start(); ++e) {
    const EpisodeLog& l = run.logs[static_cast<std::size_t>(e)];
    const ChainCurriculum::Pair p = replay.draw(replay.weights(), stream_seed(t.seed, e, 5));
    EXPECT_EQ(l.stair_height_m, p.height_m) << "episode " << e;
    ASSERT_FALSE(l.configurations.empty());
    EXPECT_EQ(l.configurations.front(), p.modules) << "episode " << e;
    firsts.insert(l.configurations.front());
    replay.record(l.stair_height_m, l.configurations.front(), l.stairs_climbed);
  }
  EXPECT_GT(firsts.size(), 1u) << "the draws are not one chain";
  const YAML::Node checkpoint = YAML::LoadFile(dir + "/checkpoint/trainer.yaml");
  EXPECT_EQ(checkpoint["chain_curriculum"].as<std::string>(), replay.outcomes_text());
  EXPECT_THROW(load_coopt_config(kCi, {"trainer.chain_curriculum=0.5", "trainer.mode=fixed"}), std::runtime_error);
  fs::remove_all(dir);
}

// trainer.config_energy_weight: before the refit the DQN is paid R2 with that
// energy weight (0: stair energy costs nothing, so a segment pays at least the
// task's R2, and one with stair energy more); the refit and the logs keep the task's.
TEST(Trainer, ConfigEnergyWeightPaysTheTrainingDqnItsOwnR2AndTheRefitTheTasks) {
  const std::vector<std::string> sets{"trainer.config_refit_episodes=2", "trainer.config_energy_weight=0"};
  const std::string dir = temp_dir("energy_weight");
  const RunResult r = run_ci(sets, dir);
  const CooptConfig c = load_coopt_config(kCi, sets);
  ASSERT_GT(c.env.task.r2.sigma3, 0);
  std::map<int, double> paid;  // per episode, the summed R2 of its decisions
  for (const DecisionLog& d : r.decisions) paid[d.episode] += d.r2;
  int cheaper = 0, refit = 0;
  for (const EpisodeLog& l : r.logs) {
    if (!paid.count(l.episode)) continue;
    const double tolerance = 1e-3 * std::max(1.0, std::abs(l.return_R2));
    if (l.episode >= c.trainer.refit_start()) {
      EXPECT_NEAR(paid[l.episode], l.return_R2, tolerance) << "refit episode " << l.episode;
      ++refit;
    } else {
      EXPECT_GE(paid[l.episode], l.return_R2 - tolerance) << "episode " << l.episode;
      cheaper += paid[l.episode] > l.return_R2 + tolerance;
    }
  }
  EXPECT_EQ(refit, 2);
  EXPECT_GT(cheaper, 0) << "no training decision was paid without the stair energy's cost";
  fs::remove_all(dir);
}

// trainer.simulation_threads: the threads step in rounds whose hand-over
// follows step counts, and every episode seeds its own random streams, so a
// (seed, thread count) pair gives the same episodes, decisions and
// evaluations every time, with or without the learner thread; the rows come
// in index order. A stop is taken at a block's end (here checkpoint_interval
// 3), and a resume, after it or after a kill, continues to the numbers of
// the uninterrupted run.
TEST(Trainer, SimulationThreadsRepeatTheirResultsAndResumeToThem) {
  const std::vector<std::string> sets{"trainer.episodes=6", "trainer.checkpoint_interval=3",
                                      "trainer.simulation_threads=2"};
  const std::string full_dir = temp_dir("sim_threads_full"), again_dir = temp_dir("sim_threads_again");
  const RunResult full = run_ci(with(sets, "trainer.learner_thread=true"), full_dir);
  const RunResult again = run_ci(with(sets, "trainer.learner_thread=false"), again_dir);
  ASSERT_EQ(full.logs.size(), 8u);
  for (int i = 0; i < 8; ++i) EXPECT_EQ(full.logs[static_cast<std::size_t>(i)].episode, i);
  EXPECT_EQ(full.episodes, again.episodes);
  ASSERT_EQ(full.decisions.size(), again.decisions.size());
  ASSERT_GE(full.decisions.size(), 8u);  // one or more an episode
  for (std::size_t i = 0; i < full.decisions.size(); ++i) {
    EXPECT_EQ(full.decisions[i].episode, again.decisions[i].episode);
    EXPECT_EQ(full.decisions[i].modules, again.decisions[i].modules);
    EXPECT_EQ(full.decisions[i].r2, again.decisions[i].r2);
  }
  EXPECT_EQ(full.evaluations, 3);  // after 3, 6 and 8 episodes
  EXPECT_EQ(read_checkpoint_info(full_dir).env_steps, read_checkpoint_info(again_dir).env_steps);
  // Both threads played: episodes 0 and 1 started together, so the second
  // one's scene is the one its index gives, not a continuation of the first.
  EXPECT_NE(full.logs[0].seed, full.logs[1].seed);

  // Ctrl-C after episode index 3 is written: the block [3, 6) is finished first.
  const CooptConfig c = load_coopt_config(kCi, with(sets, "trainer.learner_thread=true"));
  const std::string dir = temp_dir("sim_threads_resume");
  RunResult part;
  run_until_stopped(c, dir, 3, part, 6);
  EXPECT_EQ(read_checkpoint_info(dir).episodes, 6);
  // kill -9 after episode index 6 is written, before the checkpoint of the block [6, 8).
  resume_until_killed(c, dir, 6, 6, part);
  RunResult rest;
  {
    Trainer t(c, dir, collecting(rest));
    t.resume();
    EXPECT_EQ(t.episodes_done(), 6);
    EXPECT_TRUE(t.run());
  }
  ASSERT_EQ(rest.episodes.size(), 2u);
  EXPECT_EQ(rest.episodes[0], full.episodes[6]);
  EXPECT_EQ(rest.episodes[1], full.episodes[7]);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(part.episodes[static_cast<std::size_t>(i)], full.episodes[static_cast<std::size_t>(i)]);

  // The DQN refit (its fresh DQN made at a block's start, the threads' copies
  // rebuilt) repeats too.
  const std::string refit_a = temp_dir("sim_threads_refit_a"), refit_b = temp_dir("sim_threads_refit_b");
  const RunResult ra = run_ci({"trainer.simulation_threads=2", "trainer.config_refit_episodes=4"}, refit_a);
  const RunResult rb =
      run_ci({"trainer.simulation_threads=2", "trainer.config_refit_episodes=4", "trainer.learner_thread=false"},
             refit_b);
  ASSERT_EQ(ra.episodes.size(), 10u);
  EXPECT_EQ(ra.episodes, rb.episodes);
  for (const std::string& d : {full_dir, again_dir, dir, refit_a, refit_b}) fs::remove_all(d);
}

// Checkpoints write the replay as segments (rl/replay_segments.hpp): only
// the transitions since the previous checkpoint, the still-needed older
// segments hard-linked. With a 400-transition buffer the ring wraps about
// twice in this run; a resume from such a checkpoint must still give the
// uninterrupted run's episodes.
TEST(Trainer, SegmentedReplayCheckpointsResumeIdenticallyAfterTheBufferWrapped) {
  const std::vector<std::string> sets{"trainer.episodes=6", "trainer.checkpoint_interval=2", "td3.buffer_size=400",
                                      "trainer.eval_interval=0"};
  const std::string full_dir = temp_dir("segments_full");
  const RunResult full = run_ci(sets, full_dir);
  ASSERT_EQ(full.episodes.size(), 8u);
  ASSERT_GT(read_checkpoint_info(full_dir).env_steps, 800) << "the buffer must wrap for this test to mean anything";
  // The newest checkpoint shares its older segment with checkpoint.old (one
  // file, two links) and holds the motion learner without its replay.
  int shared = 0, segments = 0;
  for (const auto& e : fs::directory_iterator(full_dir + "/checkpoint")) {
    const std::string name = e.path().filename().string();
    if (name.rfind("motion-replay-", 0) != 0) continue;
    ++segments;
    if (fs::exists(full_dir + "/checkpoint.old/" + name)) {
      EXPECT_TRUE(fs::equivalent(e.path(), full_dir + "/checkpoint.old/" + name)) << name;
      ++shared;
    }
  }
  EXPECT_GE(segments, 2);
  EXPECT_GE(shared, 1);
  EXPECT_TRUE(fs::exists(full_dir + "/checkpoint/motion-replay.yaml"));
  EXPECT_TRUE(fs::exists(full_dir + "/checkpoint/config_model-replay.yaml"));

  // Stopped after 5 episodes (checkpoints after 2, 4 and at the stop), resumed to the end.
  const std::string dir = temp_dir("segments_resume");
  const CooptConfig c = load_coopt_config(kCi, sets);
  RunResult part;
  run_until_stopped(c, dir, 4, part);
  {
    Trainer t(c, dir, collecting(part));
    t.resume();
    EXPECT_EQ(t.episodes_done(), 5);
    EXPECT_TRUE(t.run());
  }
  EXPECT_EQ(part.episodes, full.episodes);
  fs::remove_all(full_dir);
  fs::remove_all(dir);
}

TEST(Trainer, ACheckpointFromAnotherConfigurationIsRefused) {
  const std::string dir = temp_dir("other");
  run_ci({"trainer.episodes=0"}, dir);
  Trainer t(load_coopt_config(kCi, {"trainer.episodes=0", "td3.batch_size=16"}), dir);
  try {
    t.resume();
    ADD_FAILURE() << "resumed a checkpoint of another configuration";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("another configuration"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("batch_size"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

// Synthetic labels: stairs for the first 30 steps, then the obstacle field.
// The detector (every 20 steps, window 10, > 70 %) must declare one switch at
// step 40; the DQN then stores the stair segment (k = 40, next mask [2, C_n])
// and decides again within the mask; the last segment ends the episode.
TEST(Trainer, SceneSwitchEndsTheSegmentAndMasksTheNextChoice) {
  const std::string dir = temp_dir("switch");
  const CooptConfig c = load_coopt_config(kCi, {"trainer.episodes=4"});
  RunResult r;
  TrainerCallbacks cb = collecting(r);
  cb.label_source = [](int step, int) { return step < 30 ? perception::kStairs : perception::kObstacleField; };
  Trainer t(c, dir, cb);
  ASSERT_TRUE(t.run());
  ASSERT_EQ(r.logs.size(), 6u);
  std::size_t d = 0;
  for (const auto& l : r.logs) {
    std::vector<DecisionLog> mine;
    while (d < r.decisions.size() && r.decisions[d].episode == l.episode) mine.push_back(r.decisions[d++]);
    if (l.steps < 40) {  // ended before the switch
      EXPECT_EQ(l.switches, 0);
      continue;
    }
    EXPECT_EQ(l.switches, 1) << "episode " << l.episode;
    ASSERT_EQ(mine.size(), 2u) << "episode " << l.episode;
    EXPECT_EQ(mine[0].step, 40);
    EXPECT_EQ(mine[0].k, 40);
    EXPECT_EQ(mine[0].modules, l.modules_total);
    EXPECT_EQ(mine[0].next_max_modules, l.modules_total);  // only shedding from here
    EXPECT_FALSE(mine[0].terminated || mine[0].truncated);
    EXPECT_LE(mine[1].modules, mine[0].modules);
    EXPECT_EQ(mine[1].k, l.steps - 40);
    EXPECT_TRUE(mine[1].terminated || mine[1].truncated);
    EXPECT_EQ(mine[1].modules, l.configurations.back());
    // R2 over both segments: all of R1, minus sigma3 * E_c (not climbed: no r_s).
    const double sigma3 = c.env.task.r2.sigma3;
    if (l.termination != "success") {
      EXPECT_NEAR(mine[0].r2 + mine[1].r2, l.return_R1 - sigma3 * l.stairs_energy_J, 1e-3 * (1 + std::abs(l.return_R1)));
    }
  }
  EXPECT_EQ(d, r.decisions.size());
  fs::remove_all(dir);
}

TEST(Trainer, FixedBaselineAndSacRun) {
  const std::string a = temp_dir("fixed"), b = temp_dir("sac");
  const RunResult fixed = run_ci({"trainer.mode=fixed", "trainer.fixed_modules=6"}, a);
  for (const auto& l : fixed.logs) {
    EXPECT_EQ(l.configurations, std::vector<int>{6});
    EXPECT_EQ(l.modules_total, 6);
  }
  EXPECT_TRUE(fixed.decisions.empty());
  EXPECT_FALSE(fs::exists(fs::path(a) / "checkpoint" / "config_model.pt"));
  const RunResult sac = run_ci({"trainer.motion_algo=sac"}, b);
  EXPECT_EQ(sac.logs.size(), 6u);
  EXPECT_FALSE(sac.decisions.empty());
  fs::remove_all(a);
  fs::remove_all(b);
}

// trainer.refit_motion_from: a run that only refits a fresh configuration
// model on another run's motion model, which it drives exactly as that run
// does (the same greedy episodes on a forced chain).
TEST(Trainer, RefitOfAnotherRunsMotionModel) {
  const std::string a = temp_dir("refit_src"), b = temp_dir("refit_only");
  run_ci({}, a);
  const std::vector<std::string> refit = {"trainer.warmup_episodes=0", "trainer.episodes=0",
                                          "trainer.config_refit_episodes=3", "trainer.refit_motion_from=" + a};
  const RunResult r = run_ci(refit, b);
  ASSERT_EQ(r.logs.size(), 3u);
  EXPECT_FALSE(r.decisions.empty());  // the fresh DQN decides and learns
  EvalRequest req;
  req.episodes = 2;
  req.seed = 77;
  req.workers = 1;
  req.forced_modules = 4;
  const auto from_a = evaluate(load_coopt_config(kCi), a, req);
  const auto from_b = evaluate(load_coopt_config(kCi, refit), b, req);
  for (int i = 0; i < 2; ++i) EXPECT_EQ(line_of(from_a[i]), line_of(from_b[i])) << i;
  {
    // Its checkpoint resumes: the learner counts this run's transitions (none), not the source's.
    Trainer resumed(load_coopt_config(kCi, refit), b);
    EXPECT_NO_THROW(resumed.resume());
    EXPECT_EQ(resumed.episodes_done(), 3);
  }
  // Only a refit may take another run's motion model.
  EXPECT_THROW(load_coopt_config(kCi, {"trainer.refit_motion_from=" + a}), std::runtime_error);
  const std::string missing = temp_dir("no_such_run"), bad = temp_dir("refit_bad");
  EXPECT_THROW(run_ci({"trainer.warmup_episodes=0", "trainer.episodes=0", "trainer.config_refit_episodes=3",
                       "trainer.refit_motion_from=" + missing},
                      bad),
               std::runtime_error);
  for (const std::string& d : {a, b, missing, bad}) fs::remove_all(d);
}

// trainer.keep_best_motion: the refit freezes the motion model of the
// periodic evaluation with the highest success (ties: higher F(H)) up to the
// refit's start, where one more evaluation is taken; the run ends with it; a
// run interrupted before the refit resumes to the same choice.
TEST(Trainer, KeepBestMotionFreezesTheBestEvaluatedMotionModel) {
  // ci: 2 warm-up + 4 training episodes, then 3 refit episodes; an evaluation after every episode.
  const std::vector<std::string> plain{"trainer.config_refit_episodes=3", "trainer.eval_interval=1",
                                       "trainer.checkpoint_interval=1"};
  const std::vector<std::string> best = with(plain, "trainer.keep_best_motion=true");
  const std::string dir = temp_dir("best"), plain_dir = temp_dir("best_plain"), cut_dir = temp_dir("best_cut");
  const RunResult r = run_ci(best, dir);
  ASSERT_EQ(r.evaluation_logs.size(), 9u);
  // The best of the evaluations after episodes 1 to 6, computed here from their episodes.
  int expected = -1;
  double best_success = -1, best_F = 0;
  for (const EvaluationLog& e : r.evaluation_logs) {
    if (e.train_episode > 6) continue;
    std::map<double, std::pair<int, int>> per_height;  // wins, episodes
    double F = 0;
    for (const EpisodeLog& l : e.episodes) {
      per_height[l.stair_height_m].first += l.success;
      per_height[l.stair_height_m].second += 1;
      F += l.F / static_cast<double>(e.episodes.size());
    }
    double success = 0;
    for (const auto& [h, wc] : per_height) success += static_cast<double>(wc.first) / wc.second / per_height.size();
    if (success > best_success || (success == best_success && F > best_F)) {
      expected = e.train_episode;
      best_success = success;
      best_F = F;
    }
  }
  // This seed's best comes before the last training episode, so the kept model differs from the last one.
  ASSERT_GE(expected, 1);
  ASSERT_LT(expected, 6);
  const YAML::Node kept = YAML::LoadFile(dir + "/checkpoint/trainer.yaml")["best_motion"];
  ASSERT_TRUE(kept);
  EXPECT_EQ(kept["episode"].as<int>(), expected);

  // The final motion model is the one after `expected` episodes: the same greedy
  // episodes on a forced chain as a run without the option stopped there, and
  // not those of that run's last model.
  const CooptConfig plain_config = load_coopt_config(kCi, plain);
  RunResult cut;
  run_until_stopped(plain_config, cut_dir, expected - 1, cut);
  const RunResult plain_run = run_ci(plain, plain_dir);
  for (int e = 0; e < 6; ++e) EXPECT_EQ(r.episodes[e], plain_run.episodes[e]) << "episode " << e;
  // The refit's episodes are driven by the kept model (the actors got its weights), not the last one.
  ASSERT_EQ(plain_run.episodes.size(), 9u);
  EXPECT_NE(std::vector<std::string>(r.episodes.begin() + 6, r.episodes.end()),
            std::vector<std::string>(plain_run.episodes.begin() + 6, plain_run.episodes.end()));
  EvalRequest req;
  req.episodes = 3;
  req.seed = 31;
  req.workers = 1;
  req.forced_modules = 4;
  const auto lines = [&](const CooptConfig& c, const std::string& run) {
    std::vector<std::string> out;
    for (const EpisodeLog& l : evaluate(c, run, req)) out.push_back(line_of(l));
    return out;
  };
  const CooptConfig best_config = load_coopt_config(kCi, best);
  EXPECT_EQ(lines(best_config, dir), lines(plain_config, cut_dir));
  EXPECT_NE(lines(best_config, dir), lines(plain_config, plain_dir));

  // Interrupted after episode 4 and resumed: the same episodes, refit included, and the same choice.
  const std::string resumed_dir = temp_dir("best_resumed");
  const RunResult resumed = run_stopped_and_resumed(best_config, resumed_dir, 3);
  EXPECT_EQ(resumed.episodes, r.episodes);
  EXPECT_EQ(YAML::LoadFile(resumed_dir + "/checkpoint/trainer.yaml")["best_motion"]["episode"].as<int>(), expected);
  EXPECT_EQ(lines(best_config, resumed_dir), lines(best_config, dir));

  // Without a refit to take it, the option is refused, naming the key.
  const std::string refused = test_support::error_of([&] { load_coopt_config(kCi, {"trainer.keep_best_motion=true"}); });
  EXPECT_NE(refused.find("trainer.keep_best_motion"), std::string::npos) << refused;
  for (const std::string& d : {dir, plain_dir, cut_dir, resumed_dir}) fs::remove_all(d);
}

// trainer.motion_average_episodes: the refit freezes the mean of the motion
// model's snapshots over the last training episodes (here after episodes 4, 5
// and 6), the run ends with it, and a run interrupted between snapshots
// resumes to the same mean.
TEST(Trainer, MotionAverageFreezesTheMeanOfTheLastSnapshots) {
  // ci: 2 warm-up + 4 training episodes, then 3 refit episodes.
  const std::vector<std::string> plain{"trainer.config_refit_episodes=3", "trainer.checkpoint_interval=1"};
  std::vector<std::string> averaged = with(plain, "trainer.motion_average_episodes=2");
  averaged.push_back("trainer.motion_average_interval=1");
  const CooptConfig plain_config = load_coopt_config(kCi, plain), averaged_config = load_coopt_config(kCi, averaged);
  const std::string dir = temp_dir("average"), plain_dir = temp_dir("average_plain");
  const RunResult r = run_ci(averaged, dir);
  const RunResult plain_run = run_ci(plain, plain_dir);
  EXPECT_EQ(YAML::LoadFile(dir + "/checkpoint/trainer.yaml")["motion_average_snapshots"].as<int>(), 3);
  // Training is the plain run's; the refit drives the mean, not the last model.
  ASSERT_EQ(r.episodes.size(), 9u);
  ASSERT_EQ(plain_run.episodes.size(), 9u);
  for (int e = 0; e < 6; ++e) EXPECT_EQ(r.episodes[e], plain_run.episodes[e]) << "episode " << e;
  EXPECT_NE(std::vector<std::string>(r.episodes.begin() + 6, r.episodes.end()),
            std::vector<std::string>(plain_run.episodes.begin() + 6, plain_run.episodes.end()));

  // The motion models of the plain run after 4, 5 and 6 episodes (runs stopped there), and their mean.
  const auto parameters = [&](const std::string& run) {
    auto learner = make_motion_learner(plain_config, 0);
    learner->load_acting_networks(run + "/checkpoint/motion_actor.pt");
    std::vector<torch::Tensor> out;
    for (const torch::Tensor& p : learner->acting_networks().parameters()) out.push_back(p.detach().clone());
    return out;
  };
  std::vector<torch::Tensor> mean;
  std::vector<std::string> cut_dirs;
  for (int done : {4, 5, 6}) {
    cut_dirs.push_back(temp_dir("average_cut" + std::to_string(done)));
    RunResult cut;
    run_until_stopped(plain_config, cut_dirs.back(), done - 1, cut);
    const std::vector<torch::Tensor> p = parameters(cut_dirs.back());
    if (mean.empty())
      for (const torch::Tensor& t : p) mean.push_back(torch::zeros_like(t));
    for (std::size_t i = 0; i < p.size(); ++i) mean[i] += p[i] / 3.0;
  }
  const std::vector<torch::Tensor> last = parameters(plain_dir), got = parameters(dir);
  ASSERT_EQ(got.size(), mean.size());
  bool differs_from_last = false;
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_TRUE(torch::allclose(got[i], mean[i], 1e-5, 1e-6)) << "parameter " << i;
    differs_from_last = differs_from_last || !torch::allclose(got[i], last[i], 1e-5, 1e-6);
  }
  EXPECT_TRUE(differs_from_last) << "the snapshots did not differ: nothing was averaged";

  // Interrupted after episode 5 (two snapshots in) and resumed: the same episodes and the same mean.
  const std::string resumed_dir = temp_dir("average_resumed");
  const RunResult resumed = run_stopped_and_resumed(averaged_config, resumed_dir, 4);
  EXPECT_EQ(resumed.episodes, r.episodes);
  const std::vector<torch::Tensor> resumed_mean = parameters(resumed_dir);
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_TRUE(torch::equal(resumed_mean[i], got[i])) << "parameter " << i;

  // Refused, naming the key: with keep_best_motion, and over more episodes than training has.
  for (const std::vector<std::string>& bad : std::vector<std::vector<std::string>>{
           {"trainer.keep_best_motion=true", "trainer.eval_interval=1"}, {"trainer.motion_average_episodes=5"}}) {
    std::vector<std::string> sets = averaged;
    sets.insert(sets.end(), bad.begin(), bad.end());
    const std::string refused = test_support::error_of([&] { load_coopt_config(kCi, sets); });
    EXPECT_NE(refused.find("trainer.motion_average_episodes"), std::string::npos) << refused;
  }
  for (const std::string& d : {dir, plain_dir, resumed_dir}) fs::remove_all(d);
  for (const std::string& d : cut_dirs) fs::remove_all(d);
}

// scene_source: classifier runs the ResNet-18 on the last 10 depth frames at
// every detector decision (here an untrained one: only the plumbing is tested).
TEST(Trainer, ClassifierSceneSourceRunsTheHierarchy) {
  const std::string dir = temp_dir("cls"), weights = temp_dir("cls_weights");
  perception::ClassifierParams p;
  p.image_size = 8;  // the ci preset's depth images
  p.width = 8;
  perception::SceneClassifier(p, 3).save(weights);
  const RunResult r = run_ci({"trainer.scene_source=classifier", "trainer.classifier_dir=" + weights,
                              "perception.classifier.image_size=8", "perception.classifier.width=8"},
                             dir);
  EXPECT_EQ(r.logs.size(), 6u);
  EXPECT_FALSE(r.decisions.empty());
  // A directory without a classifier is refused when the run starts, naming the key.
  const std::string refused = test_support::error_of([&] {
    run_ci({"trainer.scene_source=classifier", "trainer.classifier_dir=" + dir + "/none",
            "perception.classifier.image_size=8", "perception.classifier.width=8"},
           temp_dir("cls_none"));
  });
  EXPECT_NE(refused.find("trainer.classifier_dir: no classifier.pt in"), std::string::npos) << refused;
  fs::remove_all(dir);
  fs::remove_all(weights);
}

TEST(Evaluate, GreedyEpisodesCycleHeightsAndDoNotDependOnWorkers) {
  const std::string dir = temp_dir("eval");
  const CooptConfig c = load_coopt_config(kCi, {"trainer.episodes=1"});
  run_ci({"trainer.episodes=1"}, dir);
  EvalRequest req;
  req.episodes = 5;
  req.seed = 123;
  req.workers = 1;
  const auto one = evaluate(c, dir, req);
  req.workers = 2;
  std::vector<int> finished;  // the progress callback: once per episode, counting up (one call at a time)
  req.on_episode_finished = [&finished](int n, int total) {
    EXPECT_EQ(total, 5);
    finished.push_back(n);
  };
  const auto two = evaluate(c, dir, req);
  req.on_episode_finished = nullptr;
  EXPECT_EQ(finished, (std::vector<int>{1, 2, 3, 4, 5}));
  ASSERT_EQ(one.size(), 5u);
  ASSERT_EQ(two.size(), 5u);
  for (int i = 0; i < 5; ++i) {
    // The first decision's segment: part of the episode, the whole of it when no switch came.
    EXPECT_GT(one[i].first_segment_steps, 0);
    EXPECT_LE(one[i].first_segment_steps, one[i].steps);
    if (one[i].switches == 0) {
      EXPECT_EQ(one[i].first_segment_steps, one[i].steps);
      EXPECT_DOUBLE_EQ(one[i].first_segment_R2, one[i].return_R2);
      EXPECT_NEAR(one[i].first_segment_R1, one[i].return_R1, 1e-6);
    }
    EXPECT_EQ(line_of(one[i]), line_of(two[i]));
    EXPECT_EQ(one[i].seed, 123u + i);
    EXPECT_NEAR(one[i].stair_height_m, (i % 3 == 0 ? 0.04 : i % 3 == 1 ? 0.06 : 0.08), 1e-9);
  }
  req.scenario = "obstacles8";
  EXPECT_EQ(evaluate(c, dir, req)[0].obstacles, 8);
  // A forced chain: the motion model drives it, the DQN neither picks nor sheds.
  ASSERT_EQ(c.trainer.mode, TrainerMode::hierarchical);
  req.scenario = "default";
  for (int modules : {3, 7}) {
    req.forced_modules = modules;
    for (const EpisodeLog& l : evaluate(c, dir, req)) {
      EXPECT_EQ(l.configurations, std::vector<int>{modules});
      EXPECT_GT(l.first_segment_steps, 0);  // also logged without a configuration model
    }
  }
  // The pilot drives: each episode is the one the scripted pilot drives alone
  // through the same scene source (motion modes from the switch detector).
  req.forced_modules = 5;
  req.pilot_drives = true;
  req.episodes = 3;
  const std::vector<EpisodeLog> piloted = evaluate(c, dir, req);
  for (int i = 0; i < req.episodes; ++i) {
    task::MultiTaskEnv env(c.env);
    task::EpisodeSpec spec = eval_spec(c, task::scenario_named("default"), static_cast<std::uint64_t>(req.seed + i), i);
    spec.configuration = make_chain(5);
    env.reset(spec);
    SceneSource scene(c);
    scene.reset(env);
    task::ScriptedPilot pilot;
    configure_pilot(c.trainer, pilot);
    pilot.plan(env);
    float action[control::kActionSize];
    control::MotionMode pilot_mode;
    double ret = 0;
    while (true) {
      pilot.act(env, action, pilot_mode);
      const task::StepOutcome& r = env.step(
          action, scene.current() == sim::kLabelStairs ? control::MotionMode::stair : control::MotionMode::flat);
      ret += r.reward;
      if (r.terminated || r.truncated) break;
      scene.step(env);
    }
    EXPECT_EQ(piloted[i].steps, env.step_count()) << i;
    EXPECT_DOUBLE_EQ(piloted[i].return_R1, ret) << i;
    EXPECT_EQ(piloted[i].configurations, std::vector<int>{5});
  }
  req.pilot_drives = false;
  EXPECT_NE(line_of(evaluate(c, dir, req)[0]), line_of(piloted[0]));  // the motion model drives otherwise
  req.forced_modules = kMaxModules + 1;
  EXPECT_THROW(evaluate(c, dir, req), std::invalid_argument);
  fs::remove_all(dir);
}

// ---- the CLI: bad input stops before a run directory exists ----

int run_cli(const std::string& args, std::string& output) { return test_support::run_comorph(args, output); }

TEST(Cli, BadConfigOrSetFailsWithTheKeyAndCreatesNoRunDirectory) {
  const std::string parent = temp_dir("cli");
  const std::string out = parent + "/run";
  std::string err;
  EXPECT_NE(run_cli("train --config " + kCi + " --set trainer.epsiodes=3 --out " + out, err), 0);
  EXPECT_NE(err.find("trainer.epsiodes"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_NE(run_cli("train --config " + kCi + " --set dqn.epsilon_start=x --out " + out, err), 0);
  EXPECT_NE(err.find("epsilon_start"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_NE(run_cli("train --config " + kCi + " --set trainer.warmup_episodes=-1 --out " + out, err), 0);
  EXPECT_NE(err.find("warmup_episodes"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_NE(run_cli("train --config " + parent + "/missing.yaml --out " + out, err), 0);
  EXPECT_FALSE(fs::exists(out));
  EXPECT_NE(run_cli("train --resume " + out, err), 0);
  EXPECT_FALSE(fs::exists(out));
  fs::remove_all(parent);
}

TEST(Cli, TrainThenEvalWritesTheRunDirectoryLayout) {
  const std::string parent = temp_dir("cli_ok");
  const std::string out = parent + "/run";
  std::string log;
  ASSERT_EQ(run_cli("train --config " + kCi + " --set trainer.episodes=1 --out " + out, log), 0) << log;
  for (const char* f : {"run.yaml", "config.yaml", "episodes.csv", "evaluations.csv", "checkpoint/trainer.yaml"})
    EXPECT_TRUE(fs::exists(fs::path(out) / f)) << f;
  std::ifstream csv(out + "/episodes.csv");
  int lines = 0;
  for (std::string l; std::getline(csv, l);) ++lines;
  EXPECT_EQ(lines, 1 + 3);  // header + 2 warm-up + 1 episode
  EXPECT_NE(run_cli("train --config " + kCi + " --out " + out, log), 0);  // exists: use --resume
  ASSERT_EQ(run_cli("eval --run " + out + " --episodes 3 --scenario obstacles7", log), 0) << log;
  EXPECT_TRUE(fs::exists(fs::path(out) / "eval-obstacles7.json"));
  EXPECT_TRUE(fs::exists(fs::path(out) / "eval-obstacles7-episodes.csv"));
  std::ifstream json(out + "/eval-obstacles7.json");
  std::ostringstream s;
  s << json.rdbuf();
  for (const char* key : {"success_rate", "\"0.04\"", "\"avg\"", "time_s", "energy_J", "configurations", "terminations"})
    EXPECT_NE(s.str().find(key), std::string::npos) << key;
  fs::remove_all(parent);
}

// The stair heights are the run's (env.scene), not the paper's three: a run
// with 0.05 and 0.1 m stairs trains, evaluates and reports both.
TEST(Cli, AConfigsOwnStairHeightsAreReportedEverywhere) {
  const std::string parent = temp_dir("cli_heights");
  const std::string out = parent + "/run";
  const std::string heights =
      " --set env.scene.stair_height_a=0.05 --set env.scene.stair_height_b=0.1 --set env.scene.stair_height_c=0.1";
  std::string log;
  ASSERT_EQ(run_cli("train --config " + kCi + heights + " --set trainer.episodes=3 --out " + out, log), 0) << log;
  EXPECT_NE(log.find("success 0.05/0.1 m = "), std::string::npos) << log;  // the periodic evaluation's line
  const std::string evaluations = test_support::read_text(out + "/evaluations.csv");
  EXPECT_EQ(evaluations.rfind("train_episode,env_steps,wall_s,episodes,success_0.05,success_0.1,success_avg,", 0), 0u)
      << evaluations;
  EXPECT_EQ(evaluations.find(",-,"), std::string::npos) << evaluations;  // both heights were evaluated
  ASSERT_EQ(run_cli("eval --run " + out + " --episodes 3", log), 0) << log;
  EXPECT_NE(log.find("0.05 m"), std::string::npos) << log;
  EXPECT_NE(log.find("0.1 m"), std::string::npos) << log;
  const std::string json = test_support::read_text(out + "/eval-default.json");
  for (const char* key : {"\"0.05\"", "\"0.1\""}) EXPECT_NE(json.find(key), std::string::npos) << key << json;
  EXPECT_EQ(json.find("\"0.04\""), std::string::npos) << json;
  ASSERT_EQ(run_cli("report " + out + " --out " + parent + "/report", log), 0) << log;
  const std::string report = test_support::read_text(parent + "/report/report.md");
  for (const char* column : {"Success 0.05 m (%)", "Success 0.1 m (%)"})
    EXPECT_NE(report.find(column), std::string::npos) << column;
  fs::remove_all(parent);
}

}  // namespace
}  // namespace comorph::coopt

namespace comorph::coopt {
namespace {

// Reduced task: 3 m of flat ground before the first riser, 100 control steps,
// a fixed 2-module chain. The greedy motion policy after 30 short episodes
// must drive towards the goal; the same run with learning switched off (a
// broken trainer) must not reach the threshold.
double final_greedy_return(const std::vector<std::string>& extra, const std::string& name) {
  std::vector<std::string> sets{"trainer.mode=fixed",       "trainer.fixed_modules=2",  "trainer.motion_image=false",
                                "trainer.warmup_episodes=3", "trainer.episodes=30",     "trainer.eval_interval=33",
                                "trainer.eval_episodes=3",   "trainer.checkpoint_interval=100",
                                "trainer.progress_interval=100", "env.task.max_steps=100", "env.scene.start_gap=3.0",
                                "td3.hidden_sizes=[64, 64]", "td3.batch_size=64",       "td3.train_frequency=1",
                                "td3.learning_starts=200",  "td3.exploration_noise_start=0.3",
                                "td3.exploration_noise_end=0.1", "td3.exploration_noise_decay=30"};
  sets.insert(sets.end(), extra.begin(), extra.end());
  const std::string dir = temp_dir(name);
  double mean = 0;
  TrainerCallbacks cb;
  cb.on_evaluation = [&mean](const EvaluationLog& e) {
    mean = 0;
    for (const auto& l : e.episodes) mean += l.return_R1 / e.episodes.size();
  };
  Trainer t(load_coopt_config(kCi, sets), dir, cb);
  EXPECT_TRUE(t.run());
  fs::remove_all(dir);
  return mean;
}

TEST(Learning, MotionModelLearnsToDriveToTheGoalOnAReducedTask) {
  // Best case: 100 steps x 32 ms at 0.2 m/s (stair mode) = 0.64 m -> R1 ~ 64 + heading ~5.
  const double trained = final_greedy_return({}, "learn");
  const double broken = final_greedy_return({"td3.learning_starts=1000000000"}, "nolearn");
  std::printf("greedy return after training %.1f, with learning off %.1f\n", trained, broken);
  EXPECT_GT(trained, 40.0);
  EXPECT_LT(broken, 40.0);
  EXPECT_GT(trained, broken + 15.0);
}

}  // namespace
}  // namespace comorph::coopt
