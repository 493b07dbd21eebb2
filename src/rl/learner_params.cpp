#include "rl/learner_params.hpp"

namespace comorph::rl {

void check_layer_widths(const YamlFields& f, const std::vector<int>& hidden_sizes) {
  for (int size : hidden_sizes)
    if (size < 1 || size > 65536) f.fail("hidden_sizes", "layer width " + std::to_string(size) + " not in [1, 65536]");
}

namespace {

// A LinearSchedule's fields <prefix>_start and _end in [0, max], _decay in steps.
void add_linear_schedule(YamlFields& f, const std::string& prefix, double& start, double& end, double& decay,
                         double max, const std::string& what, const std::string& unit) {
  f.add(prefix + "_start", &start, 0.0, max, what + " at the start");
  f.add(prefix + "_end", &end, 0.0, max, what + " after the decay");
  f.add(prefix + "_decay", &decay, 0.0, 1e12, unit + " to decay over, linearly; 0 = constant " + prefix + "_end");
}

// TD3's and SAC's exploration_noise_correlation (rl/off_policy.hpp, step_unit_noise).
void add_noise_correlation_field(YamlFields& f, double& rho) {
  f.add("exploration_noise_correlation", &rho, 0.0, 0.9999,
        "correlation of the exploration noise (and of the random warm-up's actions) between steps: 0 = white, "
        "> 0 AR(1) forgetting over -1/ln(rho) steps");
}

// The learner's fields, read from `node`, then the shared checks.
template <class Config>
Config read_learner_config(const YAML::Node& node, const std::string& source) {
  Config c;
  YamlFields f(source);
  add_fields(f, c);
  f.apply(node);
  check_shared_learner_fields(f, c);
  return c;
}

}  // namespace

void add_fields(YamlFields& f, DqnConfig& c) {
  add_shared_learner_fields(f, c);
  f.add("discount_per", &c.discount_per,
        "what gamma discounts: step (gamma^k over a transition's k env steps) | decision (once per transition, "
        "the paper's Algorithm 1)");
  f.add("learning_rate", &c.learning_rate, kMinPositive, 1.0, "Adam step size");
  f.add("adam_epsilon", &c.adam_epsilon, 1e-20, 1.0, "Adam's epsilon");
  f.add("weight_decay", &c.weight_decay, 0.0, 1000.0,
        "decoupled weight decay (AdamW): each update shrinks the weights by 1 - learning_rate x this; 0 = Adam");
  f.add("target_update_interval", &c.target_update_interval, 1, 1000000000, "updates between target syncs");
  add_linear_schedule(f, "epsilon", c.epsilon_start, c.epsilon_end, c.epsilon_decay, 1.0,
                      "probability of a random choice", "stored transitions");
  f.add("loss", &c.loss, "loss on the TD error: huber (smooth L1, delta 1) or mse (squared)");
  f.add("double_dqn", &c.double_dqn, "pick the next action with the online network (double DQN)");
  f.add("ensemble_size", &c.ensemble_size, 1, 64,
        "Q networks trained on the same batches from their own initial weights; acting and targets use their mean");
  f.add("reward_scale", &c.reward_scale, 1e-9, 1e9,
        "the networks learn Q in units of reward x this (the greedy choice is unchanged); < 1 for returns of hundreds");
}

void add_fields(YamlFields& f, Td3Config& c) {
  add_shared_learner_fields(f, c);
  add_actor_critic_fields(f, c);
  f.add("policy_delay", &c.policy_delay, 1, 1000000, "critic updates per actor and target update (d)");
  f.add("policy_noise", &c.policy_noise, 0.0, 10.0, "std of the target smoothing noise, action units");
  f.add("noise_clip", &c.noise_clip, 0.0, 10.0, "clip of the target smoothing noise");
  add_linear_schedule(f, "exploration_noise", c.exploration_noise_start, c.exploration_noise_end,
                      c.exploration_noise_decay, 10.0, "std of the exploration noise, action units",
                      "transitions or episodes (exploration_noise_unit)");
  f.add("exploration_noise_unit", &c.exploration_noise_unit, "what exploration_noise_decay counts");
  add_noise_correlation_field(f, c.exploration_noise_correlation);
  f.add("bc_weight", &c.bc_weight, 0.0, 1000.0,
        "weight of behaviour cloning towards the transitions' target actions (TD3+BC); 0 = plain TD3");
  f.add("bc_decay_updates", &c.bc_decay_updates, std::int64_t(0), std::int64_t(1) << 40,
        "actor updates over which bc_weight falls linearly to 0; 0 = constant");
  f.add("actor_q_weight", &c.actor_q_weight, 0.0, 1.0,
        "weight of the Q term in the actor loss: 1 = TD3 (+BC), 0 = imitation of the targets alone");
}

void add_fields(YamlFields& f, SacConfig& c) {
  add_shared_learner_fields(f, c);
  add_actor_critic_fields(f, c);
  f.add("alpha_learning_rate", &c.alpha_learning_rate, kMinPositive, 1.0, "Adam step size of log(alpha)");
  f.add("policy_frequency", &c.policy_frequency, 1, 1000000,
        "critic updates between actor rounds (each of this many steps)");
  f.add("target_network_frequency", &c.target_network_frequency, 1, 1000000,
        "critic updates between soft target updates");
  f.add("alpha", &c.alpha, kMinPositive, 1000.0, "entropy temperature (the initial value when autotuned)");
  add_noise_correlation_field(f, c.exploration_noise_correlation);
  f.add("autotune_alpha", &c.autotune_alpha, "learn alpha towards the target entropy");
  f.add("target_entropy_scale", &c.target_entropy_scale, -100.0, 100.0,
        "target entropy = -scale * action dimensions, nats");
  f.add("log_std_min", &c.log_std_min, -20.0, 10.0, "lower bound of the actor's log std");
  f.add("log_std_max", &c.log_std_max, -20.0, 10.0, "upper bound of the actor's log std");
}

DqnConfig DqnConfig::from_yaml(const YAML::Node& node, const std::string& source) {
  return read_learner_config<DqnConfig>(node, source);
}

Td3Config Td3Config::from_yaml(const YAML::Node& node, const std::string& source) {
  return read_learner_config<Td3Config>(node, source);
}

SacConfig SacConfig::from_yaml(const YAML::Node& node, const std::string& source) {
  const SacConfig c = read_learner_config<SacConfig>(node, source);
  if (!(c.log_std_min < c.log_std_max)) YamlFields(source).fail("log_std_max", "must be above log_std_min");
  return c;
}

}  // namespace comorph::rl
