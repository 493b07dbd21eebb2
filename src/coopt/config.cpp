#include "coopt/config.hpp"

#include <filesystem>
#include <stdexcept>

#include "sim/params.hpp"
#include "common/resources.hpp"
#include "common/yaml_fields.hpp"
#include "rl/registry.hpp"

namespace comorph::coopt {
namespace {

[[noreturn]] void fail(const std::string& source, const std::string& key, const std::string& what) {
  throw std::runtime_error(source + ": field '" + quote_value(key) + "': " + what);
}

// Sets root[a][b][c] = value for "a.b.c=value" (maps created as needed).
void apply_set(YAML::Node& root, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw std::runtime_error("--set '" + quote_value(assignment) +
                             "': expected key=value (dotted key, e.g. trainer.episodes=10)");
  const std::string key = assignment.substr(0, eq);
  const std::string value = assignment.substr(eq + 1);
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const auto dot = key.find('.', start);
    parts.push_back(key.substr(start, dot == std::string::npos ? std::string::npos : dot - start));
    if (parts.back().empty()) throw std::runtime_error("--set '" + quote_value(assignment) + "': empty key component");
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  const YAML::Node parsed = parse_yaml(value, "--set " + quote_value(key) + " value '" + quote_value(value) + "'");
  YAML::Node node = root;
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    YAML::Node child = node[parts[i]];
    if (!child.IsDefined() || child.IsNull()) {
      node[parts[i]] = YAML::Node(YAML::NodeType::Map);
      child = node[parts[i]];
    }
    if (!child.IsMap())
      throw std::runtime_error("--set " + quote_value(key) + ": '" + quote_value(parts[i]) + "' is not a section");
    node.reset(child);
  }
  node[parts.back()] = parsed;
}

void check_keys(const YAML::Node& node, const std::string& source, const std::string& prefix,
                const std::vector<std::string>& allowed) {
  if (!node || node.IsNull()) return;
  if (!node.IsMap()) fail(source, prefix.empty() ? "<root>" : prefix, "expected a mapping");
  for (const auto& kv : node) {
    const std::string k = kv.first.as<std::string>();
    bool ok = false;
    for (const auto& a : allowed) ok = ok || a == k;
    if (!ok) fail(source, prefix.empty() ? k : prefix + "." + k, "unknown field");
  }
}

template <typename T>
void read_scalar(const YAML::Node& section, const std::string& source, const std::string& prefix,
                 const std::string& key, T& field) {
  const YAML::Node v = section[key];
  if (!v) return;
  if (!v.IsScalar()) fail(source, prefix + "." + key, "expected a scalar");
  try {
    field = v.as<T>();
  } catch (const YAML::Exception&) {
    fail(source, prefix + "." + key, "bad value '" + quote_value(v.Scalar()) + "'");
  }
}

void one_of(const std::string& source, const std::string& key, const std::string& value,
            const std::vector<std::string>& allowed) {
  for (const auto& a : allowed)
    if (a == value) return;
  std::string list;
  for (const auto& a : allowed) list += (list.empty() ? "" : " | ") + a;
  fail(source, key, "'" + quote_value(value) + "' is not one of " + list);
}

std::string dump(const YAML::Node& n) {
  if (!n || n.IsNull()) return "";
  YAML::Emitter e;
  e << n;
  return e.c_str();
}

TrainerParams read_trainer(const YAML::Node& n, const std::string& source) {
  TrainerParams p;
  const std::string pre = "trainer";
  check_keys(n, source, pre,
             {"mode", "fixed_modules", "motion_algo", "seed", "warmup_episodes", "episodes", "sync_interval",
              "learner_thread", "torch_threads", "motion_image", "config_vector", "scene_source",
              "motion_clearance", "normalize_state", "decision_camera", "warmup_policy", "warmup_noise",
              "scripted_interval", "pilot_random_configs", "pilot_gait_per_modules", "pilot_labels",
              "greedy_motion_interval", "config_learns_from", "config_target",
              "config_refit_episodes",
              "classifier_dir", "scenario", "stair_height", "eval_interval", "eval_episodes", "eval_seed",
              "checkpoint_interval", "progress_interval", "env_dir"});
  if (!n || n.IsNull()) return p;
  // Numbers with ranges through YamlFields (names the key and the range).
  YamlFields f(source);
  YAML::Node numbers(YAML::NodeType::Map);
  const std::vector<std::string> strings{"mode",     "motion_algo", "scene_source", "classifier_dir",
                                         "scenario", "env_dir",     "warmup_policy", "config_learns_from",
                                         "config_target"};
  for (const auto& kv : n) {
    const std::string k = kv.first.as<std::string>();
    bool is_string = false;
    for (const auto& s : strings) is_string = is_string || s == k;
    if (!is_string) numbers[k] = kv.second;
  }
  f.add(pre + ".fixed_modules", &p.fixed_modules, kMinModules, kMaxModules);
  f.add(pre + ".seed", &p.seed, 0, 2000000000);
  f.add(pre + ".warmup_episodes", &p.warmup_episodes, 0, 10000000);
  f.add(pre + ".episodes", &p.episodes, 0, 10000000);
  f.add(pre + ".sync_interval", &p.sync_interval, 1, 100000);
  f.add(pre + ".learner_thread", &p.learner_thread);
  f.add(pre + ".torch_threads", &p.torch_threads, 1, 64);
  f.add(pre + ".motion_image", &p.motion_image);
  f.add(pre + ".config_vector", &p.config_vector);
  f.add(pre + ".motion_clearance", &p.motion_clearance);
  f.add(pre + ".normalize_state", &p.normalize_state);
  f.add(pre + ".decision_camera", &p.decision_camera);
  f.add(pre + ".warmup_noise", &p.warmup_noise, 0.0, 2.0);
  f.add(pre + ".scripted_interval", &p.scripted_interval, 0, 10000000);
  f.add(pre + ".pilot_random_configs", &p.pilot_random_configs);
  f.add(pre + ".pilot_gait_per_modules", &p.pilot_gait_per_modules);
  f.add(pre + ".pilot_labels", &p.pilot_labels);
  f.add(pre + ".greedy_motion_interval", &p.greedy_motion_interval, 0, 10000000);
  f.add(pre + ".config_refit_episodes", &p.config_refit_episodes, 0, 10000000);
  f.add(pre + ".stair_height", &p.stair_height, 0, 0.5);
  f.add(pre + ".eval_interval", &p.eval_interval, 0, 10000000);
  f.add(pre + ".eval_episodes", &p.eval_episodes, 1, 100000);
  f.add(pre + ".eval_seed", &p.eval_seed, 0, 2000000000);
  f.add(pre + ".checkpoint_interval", &p.checkpoint_interval, 1, 10000000);
  f.add(pre + ".progress_interval", &p.progress_interval, 1, 10000000);
  f.apply(numbers, pre + ".");
  for (const auto& s : strings) read_scalar(n, source, pre, s, s == "mode" ? p.mode
                                                               : s == "motion_algo" ? p.motion_algo
                                                               : s == "scene_source" ? p.scene_source
                                                               : s == "classifier_dir" ? p.classifier_dir
                                                               : s == "scenario" ? p.scenario
                                                               : s == "warmup_policy" ? p.warmup_policy
                                                               : s == "config_learns_from" ? p.config_learns_from
                                                               : s == "config_target" ? p.config_target
                                                                                 : p.env_dir);
  one_of(source, pre + ".mode", p.mode, {"hierarchical", "fixed"});
  if (!rl::has_learner(p.motion_algo) || rl::learner_entry(p.motion_algo).actions != rl::ActionKind::kContinuous) {
    std::string names;
    for (const std::string& n : rl::learner_names())
      if (rl::learner_entry(n).actions == rl::ActionKind::kContinuous) names += (names.empty() ? "" : " | ") + n;
    fail(source, pre + ".motion_algo", "'" + quote_value(p.motion_algo) + "' is not one of " + names +
                                           " (the registered learners of continuous actions)");
  }
  one_of(source, pre + ".scene_source", p.scene_source, {"ground_truth", "classifier"});
  one_of(source, pre + ".scenario", p.scenario, {"default", "obstacles7", "obstacles8", "mixed"});
  one_of(source, pre + ".warmup_policy", p.warmup_policy, {"random", "scripted"});
  one_of(source, pre + ".config_learns_from", p.config_learns_from, {"all", "model", "greedy"});
  one_of(source, pre + ".config_target", p.config_target, {"bootstrap", "return"});
  if (p.config_learns_from == "greedy" && p.greedy_motion_interval < 1)
    fail(source, pre + ".config_learns_from", "greedy needs trainer.greedy_motion_interval >= 1");
  // A run without a single episode would end at once with no checkpoint to resume or evaluate.
  if (p.warmup_episodes + p.episodes < 1)
    fail(source, pre + ".episodes", "warmup_episodes + episodes must be at least 1");
  if (p.config_refit_episodes > 0 && p.mode != "hierarchical")
    fail(source, pre + ".config_refit_episodes", "needs trainer.mode hierarchical (a fixed chain has no DQN)");
  if (p.scene_source == "classifier") {
    if (p.classifier_dir.empty())
      fail(source, pre + ".classifier_dir", "scene_source: classifier needs the directory of a trained classifier");
    if (!std::filesystem::exists(std::filesystem::path(p.classifier_dir) / "classifier.pt"))
      fail(source, pre + ".classifier_dir", "no classifier.pt in '" + quote_value(p.classifier_dir) +
                                                "' (train one with `comorph classifier train`)");
  }
  return p;
}

EvalParams read_eval(const YAML::Node& n, const std::string& source) {
  EvalParams p;
  YamlFields f(source);
  f.add("eval.episodes", &p.episodes, 1, 1000000);
  f.add("eval.seed", &p.seed, 0, 2000000000);
  f.add("eval.workers", &p.workers, 0, 256);
  f.apply(n, "eval.");
  return p;
}

task::EnvConfig read_env(const YAML::Node& n, const std::string& source, const std::string& env_dir) {
  task::EnvConfig c = task::load_env_config(env_dir);
  check_keys(n, source, "env", {"robot", "scene", "motion", "task"});
  if (!n || n.IsNull()) return c;
  if (n["robot"]) c.robot = sim::robot_params_from_yaml(dump(n["robot"]), source + ": env.robot", c.robot);
  if (n["scene"]) c.scene = sim::scene_params_from_yaml(dump(n["scene"]), source + ": env.scene", c.scene);
  if (n["motion"])
    c.motion = control::motion_params_from_yaml(dump(n["motion"]), source + ": env.motion", c.motion);
  if (n["task"]) c.task = task::task_params_from_yaml(dump(n["task"]), source + ": env.task", c.task);
  return c;
}

}  // namespace

void scenario_settings(const std::string& scenario, int& obstacles, bool& mixed) {
  mixed = false;
  obstacles = -1;
  if (scenario == "default") return;
  if (scenario == "obstacles7") obstacles = 7;
  else if (scenario == "obstacles8") obstacles = 8;
  else if (scenario == "mixed") mixed = true;
  else throw std::runtime_error("unknown scenario '" + quote_value(scenario) + "' (default | obstacles7 | obstacles8 | mixed)");
}

CooptConfig coopt_config_from_text(const std::string& text, const std::string& source,
                                   const std::vector<std::string>& sets) {
  YAML::Node root = parse_yaml(text, source);  // also refuses a key given twice
  if (!root || root.IsNull()) root = YAML::Node(YAML::NodeType::Map);
  if (!root.IsMap()) throw std::runtime_error(source + ": expected a mapping of sections");
  for (const auto& s : sets) apply_set(root, s);
  const std::string src = sets.empty() ? source : source + " (with --set)";
  check_keys(root, src, "", {"trainer", "td3", "sac", "dqn", "env", "perception", "eval"});

  CooptConfig c;
  c.trainer = read_trainer(root["trainer"], src);
  c.eval = read_eval(root["eval"], src);
  const std::string env_dir =
      c.trainer.env_dir.empty() ? resource_path("configs/sim") : c.trainer.env_dir;
  c.env = read_env(root["env"], src, env_dir);
  c.env_dir = env_dir;
  c.env_text = task::env_files_text(env_dir);
  c.perception = perception::perception_config_from_yaml(root["perception"], src + ": perception");
  if (const std::string e = c.perception.switch_detector.validate(); !e.empty())
    throw std::runtime_error(src + ": perception.switch_detector: " + e);
  if (c.trainer.scene_source == "classifier" &&
      c.perception.classifier.image_size != c.env.robot.depth_width)
    throw std::runtime_error(src + ": perception.classifier.image_size must equal env.robot.depth_width");
  if (c.env.robot.depth_width != c.env.robot.depth_height)
    throw std::runtime_error(src + ": env.robot: depth images must be square for the CNN encoders");

  // Learner sections: parsed now so that a misspelt hyperparameter stops the
  // run before anything is written. The sections of the learners this run
  // uses must be there: their defaults are not a run's hyperparameters (and
  // td3's default random_action_steps would be refused below).
  const auto require_section = [&](const std::string& name, const std::string& needed_by, const std::string& what) {
    if (!root[name] || root[name].IsNull())
      throw std::runtime_error(src + ": no '" + name + ":' section: " + needed_by + " needs the " + what +
                               "'s hyperparameters there (configs/quick.yaml has them)");
  };
  if (c.trainer.motion_algo == "td3" || c.trainer.motion_algo == "sac")  // the typed sections; others: their defaults
    require_section(c.trainer.motion_algo, "trainer.motion_algo " + c.trainer.motion_algo, "motion model");
  if (c.trainer.mode == "hierarchical") require_section("dqn", "trainer.mode hierarchical", "configuration model");
  const auto given = [&](const char* name) { return root[name] && !root[name].IsNull(); };
  c.td3 = rl::Td3Config::from_yaml(root["td3"], src + ": td3");
  c.sac = rl::SacConfig::from_yaml(root["sac"], src + ": sac");
  c.dqn = rl::DqnConfig::from_yaml(root["dqn"], src + ": dqn");
  if (given("td3") && (c.td3.random_action_episodes != 0 || c.td3.random_action_steps != 0))
    throw std::runtime_error(src + ": field 'td3.random_action_episodes/steps': must be 0, "
                                   "the warm-up is trainer.warmup_episodes (both models)");
  if (given("sac") && (c.sac.random_action_episodes != 0 || c.sac.random_action_steps != 0))
    throw std::runtime_error(src + ": field 'sac.random_action_episodes/steps': must be 0, "
                                   "the warm-up is trainer.warmup_episodes (both models)");
  c.text = dump(root);
  c.preset = std::filesystem::path(source).stem().string();
  return c;
}

CooptConfig load_coopt_config(const std::string& path, const std::vector<std::string>& sets) {
  return coopt_config_from_text(read_text_file(path), path, sets);
}

}  // namespace comorph::coopt
