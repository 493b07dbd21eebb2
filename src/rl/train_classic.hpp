// A plain training loop for any Env and Learner, the greedy evaluation, and
// the `comorph classic` run (Pendulum-v1 / CartPole-v1 with TD3, SAC, DQN).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "rl/env.hpp"
#include "rl/learner.hpp"

namespace comorph::rl {

// "pendulum" | "cartpole"; throws naming the value otherwise.
std::unique_ptr<Env> make_classic_env(const std::string& name);

// A registered learner (rl/registry.hpp: "td3", "sac", "dqn", ...) for an
// environment with these specs; hyperparameters from `config` (a YAML
// mapping; missing fields keep the struct defaults).
std::unique_ptr<Learner> make_learner(const std::string& algorithm, const ObservationSpec& observation,
                                      const ActionSpec& action, const YAML::Node& config,
                                      const std::string& config_source, std::uint64_t seed);

// The YAML preset of an env/algorithm pair: configs/rl/<env>_<algo>.yaml.
std::string classic_config_path(const std::string& env, const std::string& algorithm);

struct TrainStats {
  std::vector<double> episode_returns;  // completed training episodes (with exploration)
  std::int64_t steps = 0;               // environment steps
  double wall_s = 0;                    // seconds
};

// Runs `steps` environment steps with exploration, storing every transition
// and doing the updates the learner asks for. `on_step(step)` (optional) is
// called after each step's updates.
TrainStats train(Env& env, Learner& learner, std::int64_t steps,
                 const std::function<void(std::int64_t)>& on_step = {});

// Returns of `episodes` episodes of the greedy policy (no learning).
std::vector<double> evaluate(Env& env, Learner& learner, int episodes);

struct ClassicOptions {
  std::string env = "pendulum";   // pendulum | cartpole
  std::string algorithm = "td3";  // td3 | sac | dqn
  std::int64_t steps = 20000;     // training environment steps
  std::uint64_t seed = 1;
  std::string config_path;        // empty = classic_config_path(env, algorithm)
  int eval_episodes = 10;
  bool log_progress = false;      // spdlog a line every 10 % of training
};

struct ClassicResult {
  double mean_return = 0;   // greedy evaluation, per episode
  double std_return = 0;    // population standard deviation
  double steps_per_s = 0;   // training environment steps per second (updates included)
  double train_wall_s = 0;  // seconds spent training
  double wall_s = 0;        // seconds, training + evaluation
  std::vector<double> eval_returns;
  TrainStats train;
};

ClassicResult run_classic(const ClassicOptions& options);

}  // namespace comorph::rl
