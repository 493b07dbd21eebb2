// The trainer's parts (trainer.hpp has the loop it runs): the run's
// TrainingState (what a checkpoint holds), its RunStore (the run directory),
// the EpisodeRunner (env, scene source, episode loop), the learner thread and
// its hand-over buffers, the pilot, the timing. Internal to coopt: the
// trainer (trainer.cpp) and its benchmarks (trainer_bench.cpp) use it.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <deque>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "coopt/episode_runner.hpp"
#include "coopt/learner_worker.hpp"
#include "coopt/run_store.hpp"
#include "coopt/simulation_threads.hpp"
#include "coopt/trainer.hpp"
#include "coopt/training_state.hpp"
#include "task/scripted_pilot.hpp"

namespace comorph::coopt {

// What the trainer does in training episode `episode`: everything follows from
// the episode's index, so any thread can play any episode.
struct EpisodePlan {
  bool warmup = false;         // one of the first warmup_episodes
  bool refit = false;          // the DQN refit: motion frozen and greedy, nothing for the motion learner
  bool scripted = false;       // the scripted pilot drives (warm-up, scripted_interval)
  bool greedy_motion = false;  // the motion model acts without exploration noise
  bool config_learns = false;  // the DQN learns from this episode's decisions
  bool random_config = false;  // configurations drawn uniformly (warm-up, pilot_random_configs)
  bool pilot = false;          // the pilot plans: BC targets, and drives when scripted
  task::EpisodeSpec spec;      // the scene (seed from trainer.seed and the index)
};
EpisodePlan plan_episode(const TrainerParams& t, int episode);
// `n` hand-over transitions of the motion model's sizes (copies into them do not allocate).
void allocate_transitions(const CooptConfig& c, std::vector<Transition>& v, std::size_t n);
// A uniform choice among the mask's valid actions (-1 when none).
int random_valid_action(const std::vector<std::uint8_t>& mask, std::mt19937_64& rng);
DecisionLog decision_log(int episode, int step, const rl::Action& a, float r2, const rl::Observation& next,
                         bool terminated, bool truncated, int k);
// trainer.config_target: return: an ended episode's decisions, with their
// segments' R2 in `r2`, become terminal transitions of the returns (each
// segment's R2 plus the later ones, discounted by gamma once more each); r2 is
// emptied.
void to_return_transitions(std::vector<Transition>& decisions, std::vector<float>& r2, double gamma);
// One transition into a learner, then the updates it asks for.
void store_and_update(rl::Learner& l, const Transition& t, int k = 1);

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

  // trainer.simulation_threads > 1 (coopt/simulation_threads.cpp): the
  // threads, the rounds' hand-over to the learner, and their timing.
  std::vector<std::unique_ptr<SimulationThread>> threads;
  std::unique_ptr<Rounds> rounds;
  std::array<Clock::duration, kPhases> threads_spent{};  // their laps, summed over threads

  Impl(const CooptConfig& c, const std::string& dir, TrainerCallbacks cb);
  ~Impl();
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
  // run()'s steps after an episode (or a block of them): its rows and
  // progress line; the periodic evaluation when due; a checkpoint.
  void log_episode(const EpisodeLog& log);
  void evaluate_in_run();
  void checkpoint_in_run();
  // trainer.refit_motion_from: that run's latest motion model into the learner and the policy.
  void take_motion_model(const std::string& run_dir);
  // run() with trainer.simulation_threads > 1 (coopt/simulation_threads.cpp).
  bool run_simulation_threads(const std::atomic<bool>* stop);
  void start_threads();
  void stop_threads();  // joins them; their laps into threads_spent
  void simulate(SimulationThread& s);  // a simulation thread's loop
  void play_in_thread(SimulationThread& s, int episode);
  void sync_threads(bool all);  // the learners' weights into the acting copies (all: also idle threads)
  void release_threads();
  void wait_for_threads(int active);
  void end_round();
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
