// Soft Actor-Critic (Haarnoja et al. 2018, with automatic entropy tuning),
// following CleanRL's sac_continuous_action.py: twin critics with soft
// (Polyak) targets, a tanh-squashed Gaussian actor whose log-std is squashed
// into [log_std_min, log_std_max], entropy temperature alpha tuned towards a
// target entropy of -target_entropy_scale * action_dims, and the actor updated
// policy_frequency times every policy_frequency critic updates.
// Actions are in [-1, 1]. The critics share one observation encoder.
// Hyperparameters: SacConfig (rl/learner_params.hpp).
#pragma once

#include <torch/torch.h>

#include <memory>

#include "rl/networks.hpp"
#include "rl/off_policy.hpp"
#include "rl/policy.hpp"

namespace comorph::rl {

class Sac final : public OffPolicyLearner {
 public:
  Sac(const ObservationSpec& observation, int action_dims, const SacConfig& config, std::uint64_t seed);
  // The acting side alone (rl/policy.hpp): the actor and its sampling, on its
  // own RNG seeded `seed`.
  static std::unique_ptr<Policy> policy(const ObservationSpec& observation, int action_dims, const SacConfig& config,
                                        std::uint64_t seed);

  void act(const Observation& observation, bool explore, Action& action) override;
  void update() override;

  double alpha() const;
  const SacConfig& config() const { return config_; }
  ActorCritic& networks() { return nets_; }

 protected:
  torch::nn::Module& acting_module() const override { return *nets_.ptr(); }
  CheckpointParts checkpoint_parts() const override;
  void write_extra(torch::serialize::OutputArchive& archive) const override;
  void read_extra(torch::serialize::InputArchive& archive) override;

 private:
  int action_dims_;
  SacConfig config_;
  ActorCritic nets_{nullptr}, target_{nullptr};
  torch::Tensor log_alpha_;
  std::unique_ptr<FlatAdam> actor_optimizer_, critic_optimizer_, alpha_optimizer_;
  // The target networks' critic parameters, laid out as critic_optimizer_'s (one Polyak step).
  mutable FlatParameters target_critic_;
};

}  // namespace comorph::rl
