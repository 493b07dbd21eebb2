// Twin Delayed DDPG (Fujimoto et al. 2018): the paper's motion model
// (Algorithm 2). Twin critics with the min of the two as target, target policy
// smoothing (clipped Gaussian noise on the target action), delayed actor and
// target updates (every policy_delay critic updates), soft (Polyak) target
// updates, Gaussian exploration noise with a linear schedule, uniform random
// actions during a warm-up. Actions are in [-1, 1] (tanh actor).
// The critics share one observation encoder (see ActorCritic in networks.hpp).
// Hyperparameters: Td3Config (rl/learner_params.hpp).
#pragma once

#include <torch/torch.h>

#include <memory>

#include "rl/networks.hpp"
#include "rl/off_policy.hpp"
#include "rl/policy.hpp"

namespace comorph::rl {

class Td3 final : public OffPolicyLearner {
 public:
  Td3(const ObservationSpec& observation, int action_dims, const Td3Config& config, std::uint64_t seed);
  // The acting side alone (rl/policy.hpp): the actor, the exploration noise
  // and the random-action warm-up, on its own RNG seeded `seed`.
  static std::unique_ptr<Policy> policy(const ObservationSpec& observation, int action_dims, const Td3Config& config,
                                        std::uint64_t seed);

  void act(const Observation& observation, bool explore, Action& action) override;
  void update() override;

  double exploration_noise() const;
  double bc_weight_now() const;  // w of the behaviour-cloning term at the current update
  const Td3Config& config() const { return config_; }
  ActorCritic& networks() { return nets_; }

 protected:
  torch::nn::Module& acting_module() const override { return *nets_.ptr(); }
  CheckpointParts checkpoint_parts() const override;

 private:
  int action_dims_;
  Td3Config config_;
  ActorCritic nets_{nullptr}, target_{nullptr};
  std::unique_ptr<FlatAdam> actor_optimizer_, critic_optimizer_;  // over nets_'s actor and critic parameters
  // The target networks' actor and critic parameters, laid out as the optimizers' (one Polyak step each).
  mutable FlatParameters target_actor_, target_critic_;
};

}  // namespace comorph::rl
