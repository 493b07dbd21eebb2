#include "rl/registry.hpp"

#include <map>
#include <stdexcept>
#include <type_traits>

#include "rl/dqn.hpp"
#include "rl/sac.hpp"
#include "rl/td3.hpp"

namespace comorph::rl {
namespace {

// The entry of one of the built-in off-policy algorithms: Config is its
// hyperparameter struct, L its learner (L::policy builds its policy).
template <class Config, class L>
LearnerEntry builtin(const std::string& name, ActionKind actions) {
  LearnerEntry e;
  e.actions = actions;
  e.default_config = [] { return std::any(Config{}); };
  e.add_fields = [](YamlFields& fields, std::any& config) { add_fields(fields, std::any_cast<Config&>(config)); };
  e.read_config = [](const YAML::Node& node, const std::string& source) {
    return std::any(Config::from_yaml(node, source));
  };
  auto config = [name](const LearnerArgs& args) {
    Config c = config_of<Config>(args, name);
    if constexpr (!std::is_same_v<Config, DqnConfig>)
      if (args.random_action_episodes >= 0) c.random_action_episodes = args.random_action_episodes;
    return c;
  };
  e.make_learner = [config](const LearnerArgs& a) -> std::unique_ptr<Learner> {
    return std::make_unique<L>(a.observation, a.action.size, config(a), a.seed);
  };
  e.make_policy = [config](const LearnerArgs& a) -> std::unique_ptr<Policy> {
    return L::policy(a.observation, a.action.size, config(a), a.seed);
  };
  return e;
}

std::map<std::string, LearnerEntry>& registry() {
  static std::map<std::string, LearnerEntry> r{
      {"dqn", builtin<DqnConfig, Dqn>("dqn", ActionKind::kDiscrete)},
      {"td3", builtin<Td3Config, Td3>("td3", ActionKind::kContinuous)},
      {"sac", builtin<SacConfig, Sac>("sac", ActionKind::kContinuous)}};
  return r;
}

const LearnerEntry& checked(const std::string& name, const LearnerArgs& args) {
  const LearnerEntry& e = learner_entry(name);
  if (args.action.kind != e.actions)
    throw std::invalid_argument(name + " needs " +
                                (e.actions == ActionKind::kDiscrete ? "discrete" : "continuous") + " actions");
  return e;
}

}  // namespace

void register_learner(const std::string& name, LearnerEntry entry) {
  if (!entry.default_config || !entry.add_fields || !entry.read_config || !entry.make_learner || !entry.make_policy)
    throw std::invalid_argument("register_learner " + name +
                                ": every function of the entry must be set (default_config, add_fields, read_config, "
                                "make_learner, make_policy)");
  registry()[name] = std::move(entry);
}

bool has_learner(const std::string& name) { return registry().count(name) > 0; }

std::vector<std::string> learner_names() {
  std::vector<std::string> names;
  for (const auto& [name, entry] : registry()) names.push_back(name);
  return names;
}

const LearnerEntry& learner_entry(const std::string& name) {
  const auto it = registry().find(name);
  if (it != registry().end()) return it->second;
  std::string list;
  for (const std::string& n : learner_names()) list += (list.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown algorithm \"" + name + "\" (registered: " + list + ")");
}

std::unique_ptr<Learner> make_learner(const std::string& name, const LearnerArgs& args) {
  return checked(name, args).make_learner(args);
}

std::unique_ptr<Policy> make_policy(const std::string& name, const LearnerArgs& args) {
  return checked(name, args).make_policy(args);
}

}  // namespace comorph::rl
