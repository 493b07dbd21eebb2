#include "coopt/config.hpp"

#include <filesystem>
#include <stdexcept>

#include "sim/params.hpp"
#include "common/resources.hpp"
#include "common/yaml_fields.hpp"
#include "rl/registry.hpp"

namespace comorph::coopt {
namespace {

// The largest count of episodes a config may give, also as the interval
// between two episode events (evaluations, checkpoints, pilot episodes, ...).
constexpr int kMaxEpisodes = 10000000;
// The largest seed a config may give (seeds are ints: this stays below 2^31 - 1).
constexpr int kMaxSeed = 2000000000;

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

std::string dump(const YAML::Node& n) {
  if (!n || n.IsNull()) return "";
  YAML::Emitter e;
  e << n;
  return e.c_str();
}

TrainerParams read_trainer(const YAML::Node& n, const std::string& source) {
  TrainerParams p;
  const std::string pre = "trainer";
  YamlFields f(source);
  f.add(pre + ".mode", &p.mode);
  f.add(pre + ".fixed_modules", &p.fixed_modules, kMinModules, kMaxModules);
  f.add(pre + ".motion_algo", &p.motion_algo);
  f.add(pre + ".seed", &p.seed, 0, kMaxSeed);
  f.add(pre + ".warmup_episodes", &p.warmup_episodes, 0, kMaxEpisodes);
  f.add(pre + ".episodes", &p.episodes, 0, kMaxEpisodes);
  f.add(pre + ".sync_interval", &p.sync_interval, 1, 100000);
  f.add(pre + ".learner_thread", &p.learner_thread);
  f.add(pre + ".torch_threads", &p.torch_threads, 1, 64);
  f.add(pre + ".simulation_threads", &p.simulation_threads, 1, 64);
  f.add(pre + ".motion_image", &p.motion_image);
  f.add(pre + ".config_vector", &p.config_vector);
  f.add(pre + ".motion_clearance", &p.motion_clearance);
  f.add(pre + ".normalize_state", &p.normalize_state);
  f.add(pre + ".decision_camera", &p.decision_camera);
  f.add(pre + ".warmup_policy", &p.warmup_policy);
  f.add(pre + ".warmup_noise", &p.warmup_noise, 0.0, 2.0);
  f.add(pre + ".scripted_interval", &p.scripted_interval, 0, kMaxEpisodes);
  f.add(pre + ".pilot_random_configs", &p.pilot_random_configs);
  f.add(pre + ".pilot_gait_per_modules", &p.pilot_gait_per_modules);
  f.add(pre + ".pilot_flat_steering", &p.pilot_flat_steering);
  f.add(pre + ".pilot_stair_steering", &p.pilot_stair_steering);
  f.add(pre + ".pilot_labels", &p.pilot_labels);
  f.add(pre + ".motion_n_step", &p.motion_n_step, 1, 1000);
  f.add(pre + ".greedy_motion_interval", &p.greedy_motion_interval, 0, kMaxEpisodes);
  f.add(pre + ".config_learns_from", &p.config_learns_from);
  f.add(pre + ".config_target", &p.config_target);
  f.add(pre + ".config_refit_episodes", &p.config_refit_episodes, 0, kMaxEpisodes);
  f.add(pre + ".refit_motion_from", &p.refit_motion_from);
  f.add(pre + ".scene_source", &p.scene_source);
  f.add(pre + ".classifier_dir", &p.classifier_dir);
  f.add(pre + ".scenario", &p.scenario);
  f.add(pre + ".stair_height", &p.stair_height, 0, 0.5);
  f.add(pre + ".eval_interval", &p.eval_interval, 0, kMaxEpisodes);
  f.add(pre + ".eval_episodes", &p.eval_episodes, 1, 100000);
  f.add(pre + ".eval_seed", &p.eval_seed, 0, kMaxSeed);
  f.add(pre + ".checkpoint_interval", &p.checkpoint_interval, 1, kMaxEpisodes);
  f.add(pre + ".progress_interval", &p.progress_interval, 1, kMaxEpisodes);
  f.add(pre + ".env_dir", &p.env_dir);
  f.apply(n, pre + ".");
  if (!rl::has_learner(p.motion_algo) || rl::learner_entry(p.motion_algo).actions != rl::ActionKind::kContinuous) {
    std::string names;
    for (const std::string& n : rl::learner_names())
      if (rl::learner_entry(n).actions == rl::ActionKind::kContinuous) names += (names.empty() ? "" : " | ") + n;
    fail(source, pre + ".motion_algo", "'" + quote_value(p.motion_algo) + "' is not one of " + names +
                                           " (the registered learners of continuous actions)");
  }
  if (p.config_learns_from == ConfigLearnsFrom::greedy && p.greedy_motion_interval < 1)
    fail(source, pre + ".config_learns_from", "greedy needs trainer.greedy_motion_interval >= 1");
  if (!p.refit_motion_from.empty()) {
    if (p.warmup_episodes != 0 || p.episodes != 0 || p.config_refit_episodes < 1)
      fail(source, pre + ".refit_motion_from",
           "a refit of another run's motion model needs trainer.warmup_episodes 0, trainer.episodes 0 and "
           "trainer.config_refit_episodes >= 1");
  } else if (p.warmup_episodes + p.episodes < 1) {
    // A run without a single episode would end at once with no checkpoint to resume or evaluate.
    fail(source, pre + ".episodes", "warmup_episodes + episodes must be at least 1");
  }
  if (p.config_refit_episodes > 0 && p.mode != TrainerMode::hierarchical)
    fail(source, pre + ".config_refit_episodes", "needs trainer.mode hierarchical (a fixed chain has no DQN)");
  if (p.scene_source == SceneSourceKind::classifier) {
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
  f.add("eval.seed", &p.seed, 0, kMaxSeed);
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

CooptConfig coopt_config_from_text(const std::string& text, const std::string& source,
                                   const std::vector<std::string>& sets) {
  YAML::Node root = parse_yaml(text, source);  // also refuses a key given twice
  if (!root || root.IsNull()) root = YAML::Node(YAML::NodeType::Map);
  if (!root.IsMap()) throw std::runtime_error(source + ": expected a mapping of sections");
  for (const auto& s : sets) apply_set(root, s);
  const std::string src = sets.empty() ? source : source + " (with --set)";
  check_keys(root, src, "", {"trainer", "td3", "sac", "dqn", "dqn_refit", "env", "perception", "eval"});

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
  if (c.trainer.scene_source == SceneSourceKind::classifier &&
      c.perception.classifier.image_size != c.env.robot.depth_width)
    throw std::runtime_error(src + ": perception.classifier.image_size must equal env.robot.depth_width");
  if (c.trainer.pilot_flat_steering == task::FlatSteering::scan && c.env.robot.scan_columns < 1)
    throw std::runtime_error(src + ": trainer.pilot_flat_steering: scan needs env.robot.scan_columns > 0 (the obstacle scan)");
  if (c.trainer.pilot_stair_steering == task::StairSteering::scan && c.env.robot.scan_columns < 1)
    throw std::runtime_error(src + ": trainer.pilot_stair_steering: scan needs env.robot.scan_columns > 0 (the obstacle scan)");
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
  if (c.trainer.mode == TrainerMode::hierarchical) require_section("dqn", "trainer.mode hierarchical", "configuration model");
  const auto given = [&](const char* name) { return root[name] && !root[name].IsNull(); };
  c.td3 = rl::Td3Config::from_yaml(root["td3"], src + ": td3");
  c.sac = rl::SacConfig::from_yaml(root["sac"], src + ": sac");
  c.dqn = rl::DqnConfig::from_yaml(root["dqn"], src + ": dqn");
  c.dqn_refit = c.dqn;
  if (given("dqn_refit")) {  // checked also where no DQN is refitted (a preset's fixed columns)
    YAML::Node merged = given("dqn") ? YAML::Clone(root["dqn"]) : YAML::Node(YAML::NodeType::Map);
    if (!root["dqn_refit"].IsMap()) throw std::runtime_error(src + ": dqn_refit: expected a mapping of dqn keys");
    for (const auto& kv : root["dqn_refit"]) merged[kv.first.as<std::string>()] = kv.second;
    c.dqn_refit = rl::DqnConfig::from_yaml(merged, src + ": dqn_refit (over dqn)");
    if (c.dqn_refit.hidden_sizes != c.dqn.hidden_sizes || c.dqn_refit.image_features != c.dqn.image_features ||
        c.dqn_refit.image_fc_size != c.dqn.image_fc_size)
      throw std::runtime_error(src + ": dqn_refit: hidden_sizes, image_features and image_fc_size must be dqn:'s "
                                     "(evaluation and export load the training or the refit DQN alike)");
  }
  if (given("td3") && (c.td3.random_action_episodes != 0 || c.td3.random_action_steps != 0))
    throw std::runtime_error(src + ": field 'td3.random_action_episodes/steps': must be 0, "
                                   "the warm-up is trainer.warmup_episodes (both models)");
  if (given("sac") && (c.sac.random_action_episodes != 0 || c.sac.random_action_steps != 0))
    throw std::runtime_error(src + ": field 'sac.random_action_episodes/steps': must be 0, "
                                   "the warm-up is trainer.warmup_episodes (both models)");
  // Where no DQN is refitted (a fixed chain, or config_refit_episodes 0) dqn_refit: is no part of the run:
  // a preset's fixed columns stay the same runs whatever it holds.
  if (given("dqn_refit") && (c.trainer.mode != TrainerMode::hierarchical || c.trainer.config_refit_episodes == 0))
    root.remove("dqn_refit");
  c.text = dump(root);
  c.preset = std::filesystem::path(source).stem().string();
  return c;
}

CooptConfig load_coopt_config(const std::string& path, const std::vector<std::string>& sets) {
  return coopt_config_from_text(read_text_file(path), path, sets);
}

}  // namespace comorph::coopt
