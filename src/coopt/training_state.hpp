// Everything a checkpoint of the trainer holds, and nothing else: both
// learners, the acting side of a one-actor run (the motion policy's counters
// and RNG, the actor's RNG), the counters and the replay segments of the last
// checkpoint.
// RunStore (coopt/run_store.hpp) writes and reads it. Internal to coopt.
#pragma once

#include <cstdint>
#include <memory>
#include <random>

#include "coopt/config.hpp"
#include "coopt/episode_runner.hpp"
#include "coopt/curriculum.hpp"
#include "rl/replay_segments.hpp"

namespace comorph::coopt {

struct TrainingState {
  // Built from the config: learner (seed), policy (seed + 1, synced from the
  // learner), configuration model (seed + 2) and its acting copy, in this
  // order (each seeds torch).
  explicit TrainingState(const CooptConfig& c);
  ~TrainingState();
  // The DQN refit's start (trainer.config_refit_episodes): a fresh
  // configuration model with the dqn_refit: hyperparameters, and its copy.
  void start_refit(const CooptConfig& c);

  std::unique_ptr<rl::Learner> motion;  // learner thread: replay, optimizers, targets
  bool motion_on_policy = false;        // its own file holds its rollout: no replay segments
  std::unique_ptr<rl::Learner> config;  // the configuration model (DQN); nullptr in fixed mode
  bool config_refit = false;            // `config` is the refit's
  // The host's acting copies, for periodic evaluations and the checkpoint's
  // motion_actor.pt. With one actor, agent.motion's counters and RNG are the
  // actor's at its last episode end (the actor continues them).
  Agent agent;
  std::mt19937_64 rng;                  // one actor: warm-up configuration choices, noise on the pilot's actions
  int episode = 0;                      // training episodes done (= rows of episodes.csv)
  int evaluations = 0;                  // periodic evaluations done (= rows of evaluations.csv)
  std::int64_t steps = 0;               // training control steps
  double wall_before = 0;               // training wall time of the earlier sessions (resume), s
  // trainer.keep_best_motion: the motion model's acting networks at its best
  // periodic evaluation so far (nullptr before the first), and that score.
  std::unique_ptr<rl::Policy> best_motion;
  int best_motion_episode = -1;         // training episodes done at that evaluation
  double best_motion_success = 0;       // its success, the stair heights' average
  double best_motion_F = 0;             // its F(H)
  // trainer.motion_average_episodes: the running mean of the motion model's
  // acting networks (nullptr before the first snapshot) and how many it holds.
  std::unique_ptr<rl::Policy> motion_average;
  int motion_average_snapshots = 0;
  StairCurriculum curriculum;           // the training episodes' recent outcomes per stair height
  ChainCurriculum chain_curriculum;     // ... and per (stair height, first chain) pair
  // The replay segments of the last checkpoint written or loaded: the next
  // checkpoint links those and writes only what was added since.
  rl::ReplaySegments motion_segments, config_segments;
};

// The models by name (rl/registry.hpp): the motion model's learner and its
// policy (td3: and sac: are the config's typed sections; another registered
// learner keeps its defaults), and the configuration model (a DQN over the
// candidate chains; none in fixed mode), and the fresh one of the DQN refit
// (trainer.config_refit_episodes; the dqn_refit: hyperparameters).
std::unique_ptr<rl::Learner> make_motion_learner(const CooptConfig& c, std::uint64_t seed);
std::unique_ptr<rl::Policy> make_motion_policy(const CooptConfig& c, std::uint64_t seed);
std::unique_ptr<rl::Learner> make_config_model(const CooptConfig& c, std::uint64_t seed);
std::unique_ptr<rl::Learner> make_refit_config_model(const CooptConfig& c);
// An acting copy of the configuration model (or of the refit one): its
// weights, counters and RNG are set by the learner host.
std::unique_ptr<rl::Policy> make_config_policy(const CooptConfig& c, bool refit);
// The hyperparameters of the configuration model that learns: the refit's (dqn_refit:) in the refit.
const rl::DqnConfig& config_model_params(const CooptConfig& c, bool refit);

}  // namespace comorph::coopt
