// The trainer's parts (trainer.hpp has the loop it runs): the run's
// TrainingState (what a checkpoint holds), its RunStore (the run directory),
// the EpisodeRunner (env, scene source, episode loop), the learner thread and
// its hand-over buffers, the pilot, the timing. Internal to coopt: the
// trainer (trainer.cpp) and its benchmarks (trainer_bench.cpp) use it.
#pragma once

#include <chrono>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "coopt/episode_runner.hpp"
#include "coopt/learner_worker.hpp"
#include "coopt/run_store.hpp"
#include "coopt/trainer.hpp"
#include "coopt/training_state.hpp"
#include "task/scripted_pilot.hpp"

namespace comorph::coopt {

struct Trainer::Impl {
  CooptConfig config;
  RunStore store;
  TrainerCallbacks callbacks;
  EpisodeRunner runner;           // env, scene source, observation buffers
  TrainingState state;            // both models, RNG, counters: what a checkpoint holds
  task::ScriptedPilot pilot;      // demonstrations and targets (warmup_policy: scripted, pilot_labels)

  // Hand-over buffers: `filling` is written by the acting thread while the
  // learner consumes the other one.
  std::vector<Transition> pending[2];
  int filling = 0, filled = 0;
  // trainer.config_target: return: the episode's decisions, stored at its end.
  // Their observations and actions, and their R2 (turned into returns).
  std::vector<Transition> episode_decisions;
  std::vector<float> episode_decision_returns;
  std::unique_ptr<LearnerWorker> worker;

  Clock::time_point started = Clock::now();
  bool run_files = false;  // config.yaml, run.yaml and the CSV files exist (written by run(), or resumed)
  std::vector<double> recent_success;  // last 20 training episodes
  // wall() at the end of the last episodes (up to 101): the ETA follows the
  // current rate, since a refit episode costs several training episodes.
  std::deque<double> recent_wall;

  // TrainerTiming: the acting thread's laps, run()'s wall time and checkpoints,
  // and the learner's job time (written by the job, read after worker->wait()).
  Laps laps;
  Clock::duration run_time{}, learner_busy{};
  int run_checkpoints = 0;
  // measure_side_rates: when set, the acting side records its transitions
  // here (preallocated) instead of handing them to the learner.
  std::vector<Transition>* record = nullptr;
  std::size_t recorded = 0;

  Impl(const CooptConfig& c, const std::string& dir, TrainerCallbacks cb);
  double wall() const;  // training wall time including resumed parts, s
  // Hands the filled transitions to the learner (after its previous job) and
  // refreshes the policy's weights from the learner.
  void hand_over();
  // Episode end: everything handed over and learnt, the policy up to date.
  void full_sync();
  // trainer.config_target: return: the ended episode's decisions into the DQN.
  void learn_episode_returns();
  EpisodeLog train_episode();  // episode `state.episode`, with its learning hooks
  EvaluationLog periodic_evaluation();
  void progress(const EpisodeLog& log);  // the progress line on stderr
  // A checkpoint of everything, after both threads are in step.
  void save_checkpoint() {
    full_sync();
    store.save_checkpoint(state, config, wall());
  }
  void load_checkpoint() {
    store.load_checkpoint(state, config);
    started = Clock::now();
    run_files = true;
  }
};

}  // namespace comorph::coopt
