// Twin Delayed DDPG (Fujimoto et al. 2018): the paper's motion model
// (Algorithm 2). Twin critics with the min of the two as target, target policy
// smoothing (clipped Gaussian noise on the target action), delayed actor and
// target updates (every policy_delay critic updates), soft (Polyak) target
// updates, Gaussian exploration noise with a linear schedule, uniform random
// actions during a warm-up. Actions are in [-1, 1] (tanh actor).
// The critics share one observation encoder (see ActorCritic in networks.hpp).
#pragma once

#include <torch/torch.h>

#include <memory>
#include <random>
#include <string>
#include <vector>

#include "rl/learner.hpp"
#include "rl/networks.hpp"
#include "rl/replay_buffer.hpp"

namespace comorph::rl {

class Td3 final : public Learner {
 public:
  Td3(const ObservationSpec& observation, int action_dims, const Td3Config& config,
      std::uint64_t seed);

  void act(const Observation& observation, bool explore, Action& action) override;
  void store(const Observation& observation, const Action& action, float reward,
             const Observation& next_observation, bool terminated, bool truncated,
             int steps = 1) override;
  int updates_due() const override;
  void update() override;
  void save(const std::string& path) const override;
  void save_without_replay(const std::string& path) const override;
  void load(const std::string& path) override;
  void save_policy(const std::string& path) const override;
  const LearnerCounters& counters() const override { return counters_; }
  double last_loss() const override { return last_loss_; }

  double exploration_noise() const;
  double bc_weight_now() const;  // w of the behaviour-cloning term at the current update
  const Td3Config& config() const { return config_; }
  ActorCritic& networks() { return nets_; }
  ReplayBuffer& replay() override { return replay_; }

 private:
  void save_to(const std::string& path, bool with_replay) const;
  torch::Tensor gaussian(std::int64_t rows, std::int64_t cols, double std);

  ObservationSpec spec_;
  int action_dims_;
  Td3Config config_;
  torch::Device device_;
  ActorCritic nets_{nullptr}, target_{nullptr};
  std::unique_ptr<torch::optim::Adam> actor_optimizer_, critic_optimizer_;
  ReplayBuffer replay_;
  std::mt19937_64 rng_;
  LearnerCounters counters_;
  double last_loss_ = 0;
};

}  // namespace comorph::rl
