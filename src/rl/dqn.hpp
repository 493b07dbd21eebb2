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
// Hyperparameters: DqnConfig (rl/learner_params.hpp).
#pragma once

#include <torch/torch.h>

#include <memory>
#include <vector>

#include "rl/networks.hpp"
#include "rl/off_policy.hpp"
#include "rl/policy.hpp"

namespace comorph::rl {

class Dqn final : public OffPolicyLearner {
 public:
  Dqn(const ObservationSpec& observation, int num_actions, const DqnConfig& config, std::uint64_t seed);
  // The acting side alone (rl/policy.hpp): the Q network and the
  // epsilon-greedy choice, on its own RNG seeded `seed`.
  static std::unique_ptr<Policy> policy(const ObservationSpec& observation, int num_actions, const DqnConfig& config,
                                        std::uint64_t seed);

  void act(const Observation& observation, bool explore, Action& action) override;
  void update() override;

  double epsilon() const;
  // TD targets r + bootstrap * max over the next state's valid actions of
  // Q_target(s', a) (Double DQN: Q_target at the online net's valid argmax).
  torch::Tensor td_target(const ReplayBatch& batch);
  // Q values of one observation (greedy diagnostics, tests), in units of reward x config().reward_scale.
  std::vector<float> q_values(const Observation& observation);
  const DqnConfig& config() const { return config_; }
  QNetwork& target_network() { return q_target_; }

 protected:
  torch::nn::Module& acting_module() const override { return *q_.ptr(); }
  int discount_steps(int steps) const override { return config_.discount_per == DiscountPer::decision ? 1 : steps; }
  CheckpointParts checkpoint_parts() const override;

 private:
  int num_actions_;
  DqnConfig config_;
  QNetwork q_{nullptr}, q_target_{nullptr};
  std::unique_ptr<FlatAdam> optimizer_;  // over q_'s parameters
  mutable FlatParameters target_;        // q_target_'s, laid out as optimizer_'s
};

}  // namespace comorph::rl
