// Everything a checkpoint of the trainer holds, and nothing else: both models
// (the motion model's learner and policy, the configuration model), the
// trainer's RNG, its counters and the replay segments of the last checkpoint.
// RunStore (coopt/run_store.hpp) writes and reads it. Internal to coopt.
#pragma once

#include <cstdint>
#include <memory>
#include <random>

#include "coopt/config.hpp"
#include "coopt/episode_runner.hpp"
#include "rl/replay_segments.hpp"

namespace comorph::coopt {

struct TrainingState {
  // Built from the config: learner (seed), policy (seed + 1, synced from the
  // learner), configuration model (seed + 2), in this order (each seeds torch).
  explicit TrainingState(const CooptConfig& c);
  ~TrainingState();

  std::unique_ptr<rl::Learner> motion;  // learner thread: replay, optimizers, targets
  bool motion_on_policy = false;        // its own file holds its rollout: no replay segments
  Agent agent;                          // acting thread: the motion policy and the configuration model
  std::mt19937_64 rng;                  // warm-up configuration choices, noise on the pilot's actions
  int episode = 0;                      // training episodes done (= rows of episodes.csv)
  int evaluations = 0;                  // periodic evaluations done (= rows of evaluations.csv)
  std::int64_t steps = 0;               // training control steps
  double wall_before = 0;               // training wall time of the earlier sessions (resume), s
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
// An acting copy of the configuration model (or of the refit one), for a
// simulation thread: its weights, counters and RNG are set by the trainer.
std::unique_ptr<rl::Policy> make_config_policy(const CooptConfig& c, bool refit);

}  // namespace comorph::coopt
