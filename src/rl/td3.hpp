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
#include <vector>

#include "rl/mlp_pass.hpp"
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
  // A vector observation's update on the CPU runs on explicit passes
  // (rl/mlp_pass.hpp); an image's (the convolutions), or any on another
  // device, on autograd. Both give the same numbers up to float rounding;
  // forcing autograd is for comparing them (a test) and timing them (bench_rl).
  void force_autograd(bool on) { force_autograd_ = on; }

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

  // Buffers of the explicit update, built at its first use; feature-major ([n, B]).
  struct ExplicitUpdate {
    MlpPass actor, critic;                          // any actor / critic network (online or target)
    std::vector<float> observation, next_observation;  // [observation, B]
    std::vector<float> critic_input;                // [observation + action, B]: the critics' cat
    std::vector<float> y, q_grad;                   // [B]
    std::vector<float> pi;                          // [A, B]: the actor's actions, each row's head
    std::vector<float> actor_output_grad;           // [heads x A, B]
    std::vector<int> head, next_head;               // [B]: each row's actor head (ObservationSpec::head_selector)
  };
  std::unique_ptr<ExplicitUpdate> explicit_;
  ReplayBatch batch_;  // reused by each update (ReplayBuffer::sample_into)
  bool force_autograd_ = false;
  void update_with_autograd(const ReplayBatch& b, const torch::Tensor& smoothing);
  void update_with_explicit_passes(const ReplayBatch& b, const torch::Tensor& smoothing);
  void actor_step_done();  // the Polyak steps after an actor step
};

}  // namespace comorph::rl
