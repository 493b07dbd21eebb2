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

struct Td3Config {
  double gamma = 0.99;                   // discount per environment step
  double actor_learning_rate = 3e-4;     // Adam step size of the actor
  double critic_learning_rate = 3e-4;    // Adam step size of the critics (+ encoder)
  int batch_size = 256;                  // transitions per update
  std::int64_t buffer_size = 1000000;    // replay capacity, transitions
  std::int64_t learning_starts = 25000;  // transitions stored before the first update
  std::int64_t random_action_steps = 25000;  // uniform random actions for this many transitions
  std::int64_t random_action_episodes = 0;   // ... and for this many episodes (paper: 300)
  int train_frequency = 1;               // stored transitions between update rounds
  int gradient_steps = 1;                // updates per round
  int policy_delay = 2;                  // critic updates per actor + target update (d)
  double tau = 0.005;                    // target Polyak weight (mu)
  double policy_noise = 0.2;             // target smoothing noise std (action units, [-1, 1])
  double noise_clip = 0.5;               // clip of the target smoothing noise
  double exploration_noise_start = 0.1;  // exploration noise std at the start
  double exploration_noise_end = 0.1;    // ... after the decay
  double exploration_noise_decay = 0;    // decay length; 0 = constant `end`
  std::string exploration_noise_unit = "transitions";  // decay counted in "transitions" or "episodes"
  double max_grad_norm = 0;              // clip gradient L2 norms; 0 = off
  // Behaviour cloning towards the demonstrator's action of the transitions that
  // carry one (Action::target; TD3+BC, Fujimoto & Gu 2021):
  // actor loss = -Q / mean|Q| + w * (squared error to the target, where there is one). w falls linearly from bc_weight to 0 over
  // bc_decay_updates actor updates (0 = constant). bc_weight 0 = plain TD3.
  double bc_weight = 0;
  std::int64_t bc_decay_updates = 0;
  std::vector<int> hidden_sizes{256, 256};  // actor and critic MLP hidden layers
  int image_features = 16;               // CNN output size (paper: 16)
  int image_fc_size = 256;               // the CNN's hidden FC layer
  bool share_encoder = true;             // actor uses the critic encoder's features (detached)
  std::string image_storage = "uint8";   // replay images: "uint8" or "float16"
  std::string device = "cpu";            // torch device of nets and batches

  static Td3Config from_yaml(const YAML::Node& node, const std::string& source);
};

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
  ActorCritic& target_networks() { return target_; }
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
