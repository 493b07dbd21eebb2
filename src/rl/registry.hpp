// Learners by name. Each entry says what the algorithm learns from (its
// action kind, on- or off-policy), declares its hyperparameters (a run's
// config has a section of the learner's name: `comorph config keys` lists
// it), and builds its Learner and its acting Policy. The classic loop (`comorph
// classic`) and the hierarchical trainer build learners only through it, so a
// new algorithm registers itself and needs no edit of either. DQN, TD3 and SAC
// are registered from the start.
#pragma once

#include <yaml-cpp/yaml.h>

#include <any>
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/yaml_fields.hpp"
#include "rl/env.hpp"
#include "rl/learner.hpp"
#include "rl/policy.hpp"

namespace comorph::rl {

// What a factory gets.
struct LearnerArgs {
  ObservationSpec observation;
  ActionSpec action;
  std::uint64_t seed = 1;
  // The algorithm's hyperparameters: its typed config (Td3Config for "td3",
  // ...; LearnerEntry::read_config makes one from YAML), or empty for its defaults.
  std::any config;
  // >= 0: uniform random actions for this many episodes, replacing the
  // config's (a trainer's warm-up); -1 keeps the config's.
  std::int64_t random_action_episodes = -1;
};

struct LearnerEntry {
  ActionKind actions = ActionKind::kContinuous;  // the action spaces it handles
  // Learns from its own latest rollout, not from a replay buffer: a trainer
  // keeps no replay segments for it (Learner::replay is not used) and
  // checkpoints it whole with save().
  bool on_policy = false;
  // Its typed config with the defaults, and the fields of such a config
  // (YamlFields::add with ranges and meanings): what read_config reads, what
  // `comorph config keys` lists and what a run's config.yaml holds.
  std::function<std::any()> default_config;
  std::function<void(YamlFields& fields, std::any& config)> add_fields;
  // The fields' values from `node` over the defaults, checked (throws naming `source`).
  std::function<std::any(const YAML::Node& node, const std::string& source)> read_config;
  std::function<std::unique_ptr<Learner>(const LearnerArgs&)> make_learner;
  std::function<std::unique_ptr<Policy>(const LearnerArgs&)> make_policy;
};

// Adds (or replaces) the entry `name`; throws std::invalid_argument when one
// of its functions is not set. Register before building learners; the
// registry is not locked against concurrent registration.
void register_learner(const std::string& name, LearnerEntry entry);
bool has_learner(const std::string& name);
// Throws std::invalid_argument naming the registered learners when `name` is not one.
const LearnerEntry& learner_entry(const std::string& name);
std::vector<std::string> learner_names();  // sorted
// The entry's factories, after checking that the action kind is one it handles.
std::unique_ptr<Learner> make_learner(const std::string& name, const LearnerArgs& args);
std::unique_ptr<Policy> make_policy(const std::string& name, const LearnerArgs& args);

// The typed config of a factory's args: the given one, or the defaults when
// none was given (throws std::invalid_argument on another type).
template <class Config>
Config config_of(const LearnerArgs& args, const std::string& name) {
  if (!args.config.has_value()) return Config{};
  if (const Config* c = std::any_cast<Config>(&args.config)) return *c;
  throw std::invalid_argument(name + ": the learner's config has the wrong type");
}

}  // namespace comorph::rl
