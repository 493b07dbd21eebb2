// Deep Q-Network (Mnih et al. 2015) for discrete actions: the paper's
// configuration model (Algorithm 1). Features:
// - target network, synced every `target_update_interval` updates (tau = 1:
//   hard copy; tau < 1: Polyak average);
// - epsilon-greedy exploration with a linear epsilon schedule;
// - invalid-action masking: act() picks only actions valid in the
//   observation's mask, and the target maximises only over the next state's
//   valid actions (stored with the transition);
// - Huber or MSE loss, optional gradient-norm clipping, optional Double DQN;
// - per-transition discount gamma^k (semi-MDP decisions that last k steps).
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

struct DqnConfig {
  double gamma = 0.99;                  // discount per environment step
  double learning_rate = 2.5e-4;        // Adam step size
  double adam_epsilon = 1e-8;           // Adam's epsilon
  int batch_size = 128;                 // transitions per update
  std::int64_t buffer_size = 10000;     // replay capacity, transitions
  std::int64_t learning_starts = 10000; // transitions stored before the first update
  int train_frequency = 10;             // stored transitions between update rounds
  int gradient_steps = 1;               // updates per round
  int target_update_interval = 500;     // updates between target syncs
  double tau = 1.0;                     // target sync: 1 = copy, <1 = Polyak weight
  double epsilon_start = 1.0;           // exploration probability at the start
  double epsilon_end = 0.05;            // ... after the decay
  double epsilon_decay = 250000;        // transitions (store() calls) to decay over
  std::string loss = "huber";           // "huber" (smooth L1, delta 1) or "mse"
  double max_grad_norm = 0;             // clip the gradient's L2 norm; 0 = off
  bool double_dqn = false;              // pick the next action with the online net
  std::vector<int> hidden_sizes{120, 84};  // MLP head; [] + image-only obs = paper's net
  int image_features = 256;             // CNN output size when an MLP head follows
  int image_fc_size = 256;              // the CNN's hidden FC layer
  std::string image_storage = "uint8";  // replay images: "uint8" or "float16"
  std::string device = "cpu";           // torch device of nets and batches

  // Fields present in `node` override the defaults; unknown fields throw.
  static DqnConfig from_yaml(const YAML::Node& node, const std::string& source);
};

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
