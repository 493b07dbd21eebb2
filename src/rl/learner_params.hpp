// The hyperparameters of the learners (DQN, TD3, SAC), each declared once in
// its struct with its default and unit, and their YAML reading with ranges.
// No torch here: a run's config (coopt/config.hpp) holds them typed.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <string>
#include <vector>

#include "common/yaml_fields.hpp"

namespace comorph::rl {

// "cpu", "cuda", "cuda:1" -> torch device; throws with the name if unknown or
// not available here (a CUDA device without CUDA, an index past the last GPU).
// (Declared with a string to keep torch out of this header.)
void check_device_name(const std::string& name);

// Smallest learning rate (and other "finite, > 0" settings) a config may give:
// the ranges below also refuse nan and inf, whose comparisons all fail.
inline constexpr double kMinPositive = 1e-12;
// Largest count of transitions or steps a config may give (~10^12).
inline constexpr std::int64_t kMaxSteps = 1000000000000;

// The fields every learner's config has (DqnConfig, Td3Config, SacConfig), bound
// under one set of YAML names with their ranges (docs/rl.md lists them); each
// from_yaml adds its own fields next to these.
template <class LearnerConfig>
void add_shared_learner_fields(YamlFields& f, LearnerConfig& c) {
  f.add("gamma", &c.gamma, 0.0, 1.0, "discount factor");
  f.add("batch_size", &c.batch_size, 1, 1000000, "transitions per update");
  f.add("buffer_size", &c.buffer_size, 1, 1000000000, "replay capacity, transitions");
  f.add("learning_starts", &c.learning_starts, 0, kMaxSteps, "transitions stored before the first update");
  f.add("train_frequency", &c.train_frequency, 1, 1000000000, "stored transitions between update rounds");
  f.add("gradient_steps", &c.gradient_steps, 1, 1000000, "updates per round");
  f.add("tau", &c.tau, 0.0, 1.0, "target network update: 1 = copy, < 1 = Polyak weight");
  f.add("max_grad_norm", &c.max_grad_norm, 0.0, 1e9, "clip of the gradients' L2 norm; 0 = off");
  f.add("hidden_sizes", &c.hidden_sizes, "widths of the MLP's hidden layers");
  f.add("image_features", &c.image_features, 1, 65536, "the image encoder's output size");
  f.add("image_fc_size", &c.image_fc_size, 1, 65536, "the image encoder's hidden fully connected layer");
  f.add("image_storage", &c.image_storage, "how the replay keeps images (value * 255 rounded, or float16)");
  f.add("device", &c.device, "torch device of networks and batches (cpu, cuda, cuda:N)");
}

// The fields TD3 and SAC (actor-critic learners) share, with their ranges.
template <class ActorCriticConfig>
void add_actor_critic_fields(YamlFields& f, ActorCriticConfig& c) {
  f.add("actor_learning_rate", &c.actor_learning_rate, kMinPositive, 1.0, "Adam step size of the actor");
  f.add("critic_learning_rate", &c.critic_learning_rate, kMinPositive, 1.0,
        "Adam step size of the critics (and the encoder)");
  f.add("random_action_steps", &c.random_action_steps, 0, kMaxSteps,
        "uniform random actions for this many transitions (a run's warm-up is trainer.warmup_episodes)");
  f.add("random_action_episodes", &c.random_action_episodes, 0, kMaxSteps,
        "... and for this many episodes (the classic loop; a run needs 0)");
  f.add("share_encoder", &c.share_encoder, "the actor uses the critic encoder's features (detached)");
}

// What the ranges of add_shared_learner_fields cannot say: layer widths
// positive (a list has no range of its own) and a known device.
void check_layer_widths(const YamlFields& f, const std::vector<int>& hidden_sizes);
template <class LearnerConfig>
void check_shared_learner_fields(const YamlFields& f, const LearnerConfig& c) {
  check_layer_widths(f, c.hidden_sizes);
  check_device_name(c.device);
}

// The learners' choices. ImageStorage: how replay buffers keep images (value
// * 255 rounded, or float16); checkpoints store its number, so keep the order.
enum class ImageStorage { kUint8, kFloat16 };
enum class DqnLoss { huber, mse };                    // DQN's loss on the TD error: smooth L1 (delta 1) or squared
enum class DiscountPer { step, decision };            // what DQN's gamma discounts
constexpr auto enum_names(ImageStorage) {
  return std::array{EnumName{ImageStorage::kUint8, "uint8"}, EnumName{ImageStorage::kFloat16, "float16"}};
}
constexpr auto enum_names(DqnLoss) {
  return std::array{EnumName{DqnLoss::huber, "huber"}, EnumName{DqnLoss::mse, "mse"}};
}
constexpr auto enum_names(DiscountPer) {
  return std::array{EnumName{DiscountPer::step, "step"}, EnumName{DiscountPer::decision, "decision"}};
}

struct DqnConfig {
  double gamma = 0.99;                  // discount per environment step (see discount_per)
  // "step": a transition that lasted k environment steps bootstraps with
  // gamma^k (semi-MDP). "decision": with gamma once per stored transition,
  // however long it lasted (the paper's Algorithm 1, line 15); a slow segment
  // then costs only through its own rewards, not through the discount.
  DiscountPer discount_per = DiscountPer::step;
  double learning_rate = 2.5e-4;        // Adam step size
  double adam_epsilon = 1e-8;           // Adam's epsilon
  // Decoupled weight decay (AdamW): each update first shrinks the weights by
  // 1 - learning_rate x this. Thousands of updates on a replay of a few
  // thousand noisy returns let the CNN fit each image's own luck: held-out
  // images of one stair height then scatter over several choices
  // (docs/results.md, "The refit DQN memorises its images"). 0 = plain Adam.
  double weight_decay = 0;
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
  DqnLoss loss = DqnLoss::huber;        // huber (smooth L1, delta 1) or mse
  double max_grad_norm = 0;             // clip the gradient's L2 norm; 0 = off
  bool double_dqn = false;              // pick the next action with the online net
  // Q networks trained side by side from their own initial weights on the
  // same batches; acting and targets use their mean: meant to average away
  // what each member fits of one image's noisy return (docs/results.md: it
  // steadied the refit's shed choice, but did not raise success).
  int ensemble_size = 1;
  // The networks learn Q in units of reward x this (targets scale r + gamma Q'
  // alike, so the greedy choice is the same). Returns of hundreds, as the
  // co-optimization's R2, need weights far from their initial scale: at Adam's
  // usual step sizes the network then fits one value per action and ignores
  // the small inputs (docs/results.md, "The refit DQN under-fits").
  double reward_scale = 1.0;
  std::vector<int> hidden_sizes{120, 84};  // MLP head; [] + image-only obs = paper's net
  int image_features = 256;             // CNN output size when an MLP head follows
  int image_fc_size = 256;              // the CNN's hidden FC layer
  ImageStorage image_storage = ImageStorage::kUint8;  // replay images: uint8 or float16
  std::string device = "cpu";           // torch device of nets and batches

  // Fields present in `node` override the defaults; unknown fields throw.
  static DqnConfig from_yaml(const YAML::Node& node, const std::string& source);
};

// The networks of TD3 and SAC (ActorCritic, rl/networks.hpp), their replay
// images and their device: the same fields with the same defaults in both.
struct ActorCriticNetworkConfig {
  std::vector<int> hidden_sizes{256, 256};  // actor and critic MLP hidden layers
  int image_features = 16;               // CNN output size (paper: 16)
  int image_fc_size = 256;               // the CNN's hidden FC layer
  bool share_encoder = true;             // actor uses the critic encoder's features (detached)
  ImageStorage image_storage = ImageStorage::kUint8;  // replay images: uint8 or float16
  std::string device = "cpu";            // torch device of nets and batches
};

// What TD3's exploration-noise decay counts (its only user, Td3Config, follows).
enum class NoiseDecayUnit { transitions, episodes };
constexpr auto enum_names(NoiseDecayUnit) {
  return std::array{EnumName{NoiseDecayUnit::transitions, "transitions"},
                    EnumName{NoiseDecayUnit::episodes, "episodes"}};
}

struct Td3Config : ActorCriticNetworkConfig {
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
  NoiseDecayUnit exploration_noise_unit = NoiseDecayUnit::transitions;  // decay counted in transitions or episodes
  // Correlation rho of the exploration noise (and of the random-action
  // warm-up's actions) between consecutive steps of an episode: 0 = white;
  // > 0 an AR(1) (Ornstein-Uhlenbeck) process of the same std per step that
  // forgets over -1 / ln(rho) steps (0.98: about 50 steps). rl/td3.cpp.
  double exploration_noise_correlation = 0;
  double max_grad_norm = 0;              // clip gradient L2 norms; 0 = off
  // Behaviour cloning towards the demonstrator's action of the transitions that
  // carry one (Action::target; TD3+BC, Fujimoto & Gu 2021):
  // actor loss = -Q / mean|Q| + w * (squared error to the target, where there is one). w falls linearly from bc_weight to 0 over
  // bc_decay_updates actor updates (0 = constant). bc_weight 0 = plain TD3.
  double bc_weight = 0;
  std::int64_t bc_decay_updates = 0;
  // Weight of the Q term in that actor loss: 1 = TD3 (+BC); 0 = the actor
  // imitates the targets alone (behaviour cloning on the replay; the critics
  // still learn, unused): what the critic adds to the imitation.
  double actor_q_weight = 1;

  static Td3Config from_yaml(const YAML::Node& node, const std::string& source);
};

struct SacConfig : ActorCriticNetworkConfig {
  double gamma = 0.99;                   // discount per environment step
  double actor_learning_rate = 3e-4;     // Adam step size of the actor
  double critic_learning_rate = 1e-3;    // Adam step size of the critics (+ encoder)
  double alpha_learning_rate = 1e-3;     // Adam step size of log(alpha)
  int batch_size = 256;                  // transitions per update
  std::int64_t buffer_size = 1000000;    // replay capacity, transitions
  std::int64_t learning_starts = 5000;   // transitions stored before the first update
  std::int64_t random_action_steps = 5000;   // uniform random actions for this many transitions
  std::int64_t random_action_episodes = 0;   // ... and for this many episodes
  int train_frequency = 1;               // stored transitions between update rounds
  int gradient_steps = 1;                // updates per round
  int policy_frequency = 2;              // critic updates between actor rounds (each of this many steps)
  int target_network_frequency = 1;      // critic updates between soft target updates
  double tau = 0.005;                    // target Polyak weight
  double alpha = 0.2;                    // entropy temperature (initial value when autotuned)
  bool autotune_alpha = true;            // learn alpha towards the target entropy
  double target_entropy_scale = 1.0;     // target entropy = -scale * action_dims (nats)
  double log_std_min = -5.0;             // actor log-std range
  double log_std_max = 2.0;
  // Correlation rho, between consecutive steps of an episode, of the unit
  // noise of the exploring policy's samples (the Gaussian's eps) and of the
  // random-action warm-up's actions: 0 = white; > 0 the AR(1) process of
  // rl/off_policy.hpp (coloured noise in SAC, as Eberhard et al. 2023).
  // Only acting; the updates draw their own white samples.
  double exploration_noise_correlation = 0;
  double max_grad_norm = 0;              // clip gradient L2 norms; 0 = off

  static SacConfig from_yaml(const YAML::Node& node, const std::string& source);
};

// Every field of a learner's config with its range and meaning: what
// from_yaml reads, `comorph config keys` lists and a run's config.yaml holds.
void add_fields(YamlFields& f, DqnConfig& c);
void add_fields(YamlFields& f, Td3Config& c);
void add_fields(YamlFields& f, SacConfig& c);

}  // namespace comorph::rl
