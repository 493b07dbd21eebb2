#include "rl/learner_params.hpp"

namespace comorph::rl {

void check_layer_widths(const YamlFields& f, const std::vector<int>& hidden_sizes) {
  for (int size : hidden_sizes)
    if (size < 1 || size > 65536) f.fail("hidden_sizes", "layer width " + std::to_string(size) + " not in [1, 65536]");
}

namespace {

// A LinearSchedule's fields <prefix>_start and _end in [0, max], _decay in steps.
void add_linear_schedule(YamlFields& f, const std::string& prefix, double& start, double& end, double& decay,
                         double max) {
  f.add(prefix + "_start", &start, 0.0, max);
  f.add(prefix + "_end", &end, 0.0, max);
  f.add(prefix + "_decay", &decay, 0.0, 1e12);
}

// The shared fields, the learner's own (add_own), then the shared checks.
template <class Config, class AddOwn>
Config read_learner_config(const YAML::Node& node, const std::string& source, AddOwn add_own) {
  Config c;
  YamlFields f(source);
  add_shared_learner_fields(f, c);
  add_own(f, c);
  f.apply(node);
  check_shared_learner_fields(f, c);
  return c;
}

}  // namespace

DqnConfig DqnConfig::from_yaml(const YAML::Node& node, const std::string& source) {
  return read_learner_config<DqnConfig>(node, source, [](YamlFields& f, DqnConfig& c) {
    f.add("learning_rate", &c.learning_rate, kMinPositive, 1.0);
    f.add("adam_epsilon", &c.adam_epsilon, 1e-20, 1.0);
    f.add("target_update_interval", &c.target_update_interval, 1, 1000000000);
    add_linear_schedule(f, "epsilon", c.epsilon_start, c.epsilon_end, c.epsilon_decay, 1.0);
    f.add("loss", &c.loss);
    f.add("double_dqn", &c.double_dqn);
    f.add("discount_per", &c.discount_per);
  });
}

Td3Config Td3Config::from_yaml(const YAML::Node& node, const std::string& source) {
  return read_learner_config<Td3Config>(node, source, [](YamlFields& f, Td3Config& c) {
    add_actor_critic_fields(f, c);
    f.add("policy_delay", &c.policy_delay, 1, 1000000);
    f.add("policy_noise", &c.policy_noise, 0.0, 10.0);
    f.add("noise_clip", &c.noise_clip, 0.0, 10.0);
    add_linear_schedule(f, "exploration_noise", c.exploration_noise_start, c.exploration_noise_end,
                        c.exploration_noise_decay, 10.0);
    f.add("exploration_noise_unit", &c.exploration_noise_unit);
    f.add("exploration_noise_correlation", &c.exploration_noise_correlation, 0.0, 0.9999);
    f.add("bc_weight", &c.bc_weight, 0.0, 1000.0);
    f.add("bc_decay_updates", &c.bc_decay_updates, std::int64_t(0), std::int64_t(1) << 40);
    f.add("actor_q_weight", &c.actor_q_weight, 0.0, 1.0);
  });
}

SacConfig SacConfig::from_yaml(const YAML::Node& node, const std::string& source) {
  const SacConfig c = read_learner_config<SacConfig>(node, source, [](YamlFields& f, SacConfig& c) {
    add_actor_critic_fields(f, c);
    f.add("alpha_learning_rate", &c.alpha_learning_rate, kMinPositive, 1.0);
    f.add("policy_frequency", &c.policy_frequency, 1, 1000000);
    f.add("target_network_frequency", &c.target_network_frequency, 1, 1000000);
    f.add("alpha", &c.alpha, kMinPositive, 1000.0);
    f.add("autotune_alpha", &c.autotune_alpha);
    f.add("target_entropy_scale", &c.target_entropy_scale, -100.0, 100.0);
    f.add("log_std_min", &c.log_std_min, -20.0, 10.0);
    f.add("log_std_max", &c.log_std_max, -20.0, 10.0);
  });
  if (!(c.log_std_min < c.log_std_max)) YamlFields(source).fail("log_std_max", "must be above log_std_min");
  return c;
}

}  // namespace comorph::rl
