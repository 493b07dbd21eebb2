// The core DQN, TD3 and SAC share: one replay buffer, the counters, the RNG,
// the device, the update schedule (learning_starts, train_frequency,
// gradient_steps), the discount of a stored transition (gamma^k), and the
// checkpoint files around each algorithm's own networks and optimizers. An
// algorithm adds act(), update(), its networks and its part of a checkpoint.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "rl/acting_state.hpp"
#include "rl/flat_adam.hpp"
#include "rl/learner.hpp"
#include "rl/networks.hpp"
#include "rl/replay_buffer.hpp"

namespace comorph::rl {

// rows x cols Gaussian noise of standard deviation `std` on `device`, drawn
// element by element from `rng` (a learner's or policy's own generator, so
// that a checkpoint restores the stream).
torch::Tensor gaussian_noise(std::int64_t rows, std::int64_t cols, double std, std::mt19937_64& rng,
                             const torch::Device& device);

// Whether an actor-critic config's random-action warm-up (random_action_steps
// transitions or random_action_episodes episodes) lasts at these counts.
inline bool in_random_warmup(std::int64_t random_action_steps, std::int64_t random_action_episodes,
                             const LearnerCounters& counters) {
  return counters.transitions < random_action_steps || counters.episodes < random_action_episodes;
}
// One step of the exploration noise's unit process in `z` (one value per
// action dimension): with correlation rho > 0 the AR(1) process
// z' = rho z + sqrt(1 - rho^2) e, e ~ N(0, 1), whose values are N(0, 1) at
// every step (an empty `z` starts from that distribution) and whose
// correlation decays over -1 / ln(rho) steps (Ornstein-Uhlenbeck sampled at
// the control interval). Held for many steps, a correlated draw explores what
// a sustained action does (a stair gait), which white noise averages away.
void step_unit_noise(double rho, int action_dims, std::mt19937_64& rng, std::vector<float>& z);

// While that warm-up lasts and the caller explores, fills `action` uniformly
// in [-1, 1] and returns true: white with rho = 0, else erf(z / sqrt 2) of
// the AR(1) process in `noise` (uniform at every step, correlated between steps).
bool random_warmup_action(std::int64_t random_action_steps, std::int64_t random_action_episodes,
                          const LearnerCounters& counters, bool explore, double rho, std::mt19937_64& rng,
                          std::vector<float>& noise, Action& action);

// The acting rule TD3 and SAC share, for the learner and its Policy: a random
// action during the random-action warm-up (returns false), else the actor's
// action_dims values, which `actor_output(out)` writes into action.continuous
// (returns true).
template <typename Config, typename ActorOutput>
bool act_continuous(const Config& c, int action_dims, const LearnerCounters& counters, bool explore,
                    std::mt19937_64& rng, ActingState& state, Action& action, ActorOutput&& actor_output) {
  action.continuous.resize(action_dims);
  if (random_warmup_action(c.random_action_steps, c.random_action_episodes, counters, explore,
                           c.exploration_noise_correlation, rng, state.noise, action))
    return false;
  actor_output(action.continuous.data());
  return true;
}

// The values of a [1, n] action tensor that `compute()` makes (under
// InferenceMode), copied into `out`.
template <typename Compute>
void copy_tensor_action(Compute&& compute, float* out) {
  torch::Tensor a;
  {
    torch::InferenceMode guard;
    a = compute().to(torch::kCPU);
  }
  std::copy(a.data_ptr<float>(), a.data_ptr<float>() + a.numel(), out);
}

// One gradient step: zero_grad, backward, the gradient's L2 norm clipped to
// max_grad_norm (0: not clipped), step; over the optimizer's own parameters.
void gradient_step(FlatAdam& optimizer, const torch::Tensor& loss, double max_grad_norm);
// Its second half, once the gradient is in the optimizer's buffer: clip, step.
void clip_and_step(FlatAdam& optimizer, double max_grad_norm);

// The twin critics' step of TD3 and SAC towards the targets y: MSE of Q1 and
// Q2 at the batch's actions, one gradient_step. The critic encoder runs once
// for both; its features of the batch are returned (the actor step reuses
// them, detached) with the loss in `loss`.
torch::Tensor twin_critic_step(ActorCritic& nets, FlatAdam& optimizer, const ReplayBatch& b,
                               const torch::Tensor& y, double max_grad_norm, double& loss);

// The actor's features of one observation (TD3, SAC acting; the caller holds
// an InferenceMode guard).
torch::Tensor actor_features_of(ActorCritic& nets, const Observation& o, const ObservationSpec& spec,
                                const torch::Device& device);

class OffPolicyLearner : public Learner {
 public:
  void store(const Observation& observation, const Action& action, float reward,
             const Observation& next_observation, bool terminated, bool truncated, int steps = 1) final;
  int updates_due() const final;
  void save(const std::string& path) const final { save_to(path, true); }
  void save_without_replay(const std::string& path) const final { save_to(path, false); }
  void load(const std::string& path) final;
  void save_policy(const std::string& path) const final;
  void load_acting_networks(const std::string& path) final;
  ReplayBuffer& replay() final { return replay_; }
  const LearnerCounters& counters() const final { return counters_; }
  const torch::nn::Module& acting_networks() const final { return acting_module(); }
  double last_loss() const final { return last_loss_; }
  const std::mt19937_64& rng() const final { return rng_; }
  void set_rng(const std::mt19937_64& rng) final { rng_ = rng; }

 protected:
  // What every off-policy config has (DqnConfig, Td3Config, SacConfig).
  struct Schedule {
    double gamma = 0.99;
    std::int64_t learning_starts = 0;
    int train_frequency = 1;
    int gradient_steps = 1;
  };
  template <class Config>
  static Schedule schedule_of(const Config& c) {
    return {c.gamma, c.learning_starts, c.train_frequency, c.gradient_steps};
  }
  // `algorithm` names the learner in its checkpoints; `networks_key` is the
  // archive entry of its acting networks (save_policy, Policy::load).
  template <class Config>
  OffPolicyLearner(std::string algorithm, std::string networks_key, const ObservationSpec& observation,
                   const ActionSpec& action, const Config& c, std::uint64_t seed)
      : spec_(observation), device_(c.device),
        replay_(observation, nonempty(algorithm, action), c.buffer_size, c.image_storage), rng_(seed),
        schedule_(schedule_of(c)), algorithm_(std::move(algorithm)), key_(std::move(networks_key)) {}

  // `action` if it has at least one action (dimension); throws naming the
  // algorithm otherwise, before the replay is sized by it.
  static const ActionSpec& nonempty(const std::string& algorithm, const ActionSpec& action);

  // Online and target networks, built by `make` after seeding torch with the
  // learner's seed (network initialisation); the target starts as a copy.
  template <class Net, class Make>
  static void build_networks(std::uint64_t seed, Net& online, Net& target, Make make) {
    torch::manual_seed(seed);
    online = make();
    target = make();
    copy_parameters(*target, *online);
  }

  // The acting networks (a module holder: const access still loads into them).
  virtual torch::nn::Module& acting_module() const = 0;
  // Adam with this learner's options over `parameters`, kept flat (rl/flat_adam.hpp).
  static std::unique_ptr<FlatAdam> make_adam(std::vector<torch::Tensor> parameters, double learning_rate,
                                             double epsilon = 1e-8, double weight_decay = 0) {
    FlatAdam::Options o;
    o.learning_rate = learning_rate;
    o.epsilon = epsilon;
    o.weight_decay = weight_decay;
    return std::make_unique<FlatAdam>(std::move(parameters), o);
  }
  // The exponent k of a stored transition's discount gamma^k, for one that
  // lasted `steps` environment steps (DQN's discount_per: decision gives 1).
  virtual int discount_steps(int steps) const { return steps; }
  // The algorithm's part of a full checkpoint, between the counters and the
  // replay: its networks (online and target) and optimizers, each under its
  // archive key, and anything else it learns (write_extra / read_extra).
  // `flat`: the target networks' flat buffers, rebound with the optimizers'
  // after a load (a module load gives parameters new storage).
  struct CheckpointParts {
    std::vector<std::pair<std::string, torch::nn::Module*>> modules;
    std::vector<std::pair<std::string, FlatAdam*>> optimizers;
    std::vector<FlatParameters*> flat;
  };
  virtual CheckpointParts checkpoint_parts() const = 0;
  virtual void write_extra(torch::serialize::OutputArchive&) const {}
  virtual void read_extra(torch::serialize::InputArchive&) {}

  ObservationSpec spec_;
  torch::Device device_;
  ReplayBuffer replay_;
  std::mt19937_64 rng_;  // replay sampling, exploration, the algorithm's noise
  ActingState acting_;  // act()'s noise state within an episode and its buffers (as a Policy's)
  LearnerCounters counters_;
  double last_loss_ = 0;

 private:
  void save_to(const std::string& path, bool with_replay) const;
  Schedule schedule_;
  std::string algorithm_, key_;
};

}  // namespace comorph::rl
