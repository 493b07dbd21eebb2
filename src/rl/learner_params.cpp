#include "rl/learner_params.hpp"

#include <stdexcept>

#include "rl/replay_buffer.hpp"  // image_storage_from_string

namespace comorph::rl {

void check_layer_widths(const YamlFields& f, const std::vector<int>& hidden_sizes) {
  for (int size : hidden_sizes)
    if (size < 1 || size > 65536) f.fail("hidden_sizes", "layer width " + std::to_string(size) + " not in [1, 65536]");
}

void check_image_storage(const std::string& name) { image_storage_from_string(name); }

DqnConfig DqnConfig::from_yaml(const YAML::Node& node, const std::string& source) {
  DqnConfig c;
  YamlFields f(source);
  add_shared_learner_fields(f, c);
  f.add("learning_rate", &c.learning_rate, kMinPositive, 1.0);
  f.add("adam_epsilon", &c.adam_epsilon, 1e-20, 1.0);
  f.add("target_update_interval", &c.target_update_interval, 1, 1000000000);
  f.add("epsilon_start", &c.epsilon_start, 0.0, 1.0);
  f.add("epsilon_end", &c.epsilon_end, 0.0, 1.0);
  f.add("epsilon_decay", &c.epsilon_decay, 0.0, 1e12);
  f.add("loss", &c.loss);
  f.add("double_dqn", &c.double_dqn);
  f.add("discount_per", &c.discount_per);
  f.apply(node);
  check_shared_learner_fields(f, c);
  if (c.loss != "huber" && c.loss != "mse")
    throw std::invalid_argument(source + ": field \"loss\" must be huber or mse, got \"" + c.loss + "\"");
  if (c.discount_per != "step" && c.discount_per != "decision")
    throw std::invalid_argument(source + ": field \"discount_per\" must be step or decision, got \"" +
                                c.discount_per + "\"");
  return c;
}

Td3Config Td3Config::from_yaml(const YAML::Node& node, const std::string& source) {
  Td3Config c;
  YamlFields f(source);
  add_shared_learner_fields(f, c);
  add_actor_critic_fields(f, c);
  f.add("policy_delay", &c.policy_delay, 1, 1000000);
  f.add("policy_noise", &c.policy_noise, 0.0, 10.0);
  f.add("noise_clip", &c.noise_clip, 0.0, 10.0);
  f.add("exploration_noise_start", &c.exploration_noise_start, 0.0, 10.0);
  f.add("exploration_noise_end", &c.exploration_noise_end, 0.0, 10.0);
  f.add("exploration_noise_decay", &c.exploration_noise_decay, 0.0, 1e12);
  f.add("exploration_noise_unit", &c.exploration_noise_unit);
  f.add("share_encoder", &c.share_encoder);
  f.add("bc_weight", &c.bc_weight, 0.0, 1000.0);
  f.add("bc_decay_updates", &c.bc_decay_updates, std::int64_t(0), std::int64_t(1) << 40);
  f.apply(node);
  check_shared_learner_fields(f, c);
  if (c.exploration_noise_unit != "transitions" && c.exploration_noise_unit != "episodes")
    throw std::invalid_argument(source + ": field \"exploration_noise_unit\" must be transitions "
                                         "or episodes, got \"" + c.exploration_noise_unit + "\"");
  return c;
}

SacConfig SacConfig::from_yaml(const YAML::Node& node, const std::string& source) {
  SacConfig c;
  YamlFields f(source);
  add_shared_learner_fields(f, c);
  add_actor_critic_fields(f, c);
  f.add("alpha_learning_rate", &c.alpha_learning_rate, kMinPositive, 1.0);
  f.add("policy_frequency", &c.policy_frequency, 1, 1000000);
  f.add("target_network_frequency", &c.target_network_frequency, 1, 1000000);
  f.add("alpha", &c.alpha, kMinPositive, 1000.0);
  f.add("autotune_alpha", &c.autotune_alpha);
  f.add("target_entropy_scale", &c.target_entropy_scale, -100.0, 100.0);
  f.add("log_std_min", &c.log_std_min, -20.0, 10.0);
  f.add("log_std_max", &c.log_std_max, -20.0, 10.0);
  f.add("share_encoder", &c.share_encoder);
  f.apply(node);
  check_shared_learner_fields(f, c);
  if (!(c.log_std_min < c.log_std_max)) f.fail("log_std_max", "must be above log_std_min");
  return c;
}

}  // namespace comorph::rl
