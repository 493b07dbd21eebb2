// Soft Actor-Critic (Haarnoja et al. 2018, with automatic entropy tuning),
// following CleanRL's sac_continuous_action.py: twin critics with soft
// (Polyak) targets, a tanh-squashed Gaussian actor whose log-std is squashed
// into [log_std_min, log_std_max], entropy temperature alpha tuned towards a
// target entropy of -target_entropy_scale * action_dims, and the actor updated
// policy_frequency times every policy_frequency critic updates.
// Actions are in [-1, 1]. The critics share one observation encoder.
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

class Sac final : public Learner {
 public:
  Sac(const ObservationSpec& observation, int action_dims, const SacConfig& config,
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

  double alpha() const;
  const SacConfig& config() const { return config_; }
  ActorCritic& networks() { return nets_; }
  ReplayBuffer& replay() override { return replay_; }

 private:
  void save_to(const std::string& path, bool with_replay) const;
  // Squashed Gaussian sample and its log-probability, from actor features.
  std::pair<torch::Tensor, torch::Tensor> sample_action(const torch::Tensor& actor_features);
  torch::Tensor standard_normal(std::int64_t rows, std::int64_t cols);

  ObservationSpec spec_;
  int action_dims_;
  SacConfig config_;
  torch::Device device_;
  ActorCritic nets_{nullptr}, target_{nullptr};
  torch::Tensor log_alpha_;
  std::unique_ptr<torch::optim::Adam> actor_optimizer_, critic_optimizer_, alpha_optimizer_;
  ReplayBuffer replay_;
  std::mt19937_64 rng_;
  LearnerCounters counters_;
  double last_loss_ = 0;
};

}  // namespace comorph::rl
