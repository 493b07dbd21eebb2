// Deep Q-Network (Mnih et al. 2015) for discrete actions: the paper's
// configuration model (Algorithm 1). Features:
// - target network, synced every `target_update_interval` updates (tau = 1:
//   hard copy; tau < 1: Polyak average);
// - epsilon-greedy exploration with a linear epsilon schedule;
// - invalid-action masking: act() picks only actions valid in the
//   observation's mask, and the target maximises only over the next state's
//   valid actions (stored with the transition);
// - Huber or MSE loss, optional gradient-norm clipping, optional Double DQN;
// - per-transition discount gamma^k (semi-MDP decisions that last k steps),
//   or gamma per decision (DqnConfig::discount_per).
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

class Dqn final : public Learner {
 public:
  Dqn(const ObservationSpec& observation, int num_actions, const DqnConfig& config,
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

  double epsilon() const;
  // TD targets r + bootstrap * max over the next state's valid actions of
  // Q_target(s', a) (Double DQN: Q_target at the online net's valid argmax).
  torch::Tensor td_target(const ReplayBatch& batch);
  // Q values of one observation (greedy diagnostics, tests).
  std::vector<float> q_values(const Observation& observation);
  const DqnConfig& config() const { return config_; }
  ReplayBuffer& replay() override { return replay_; }
  QNetwork& q_network() { return q_; }
  QNetwork& target_network() { return q_target_; }

 private:
  void save_to(const std::string& path, bool with_replay) const;
  ObservationSpec spec_;
  int num_actions_;
  DqnConfig config_;
  torch::Device device_;
  QNetwork q_{nullptr}, q_target_{nullptr};
  std::unique_ptr<torch::optim::Adam> optimizer_;
  ReplayBuffer replay_;
  std::mt19937_64 rng_;
  LearnerCounters counters_;
  double last_loss_ = 0;
};

}  // namespace comorph::rl
