#include "coopt/config.hpp"

#include <algorithm>
#include <any>
#include <filesystem>
#include <stdexcept>
#include <type_traits>

#include "sim/params.hpp"
#include "common/resources.hpp"
#include "common/yaml_fields.hpp"
#include "coopt/segment.hpp"
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
    const std::string k = kv.first.Scalar();  // parse_yaml refused keys that are not names
    bool ok = false;
    for (const auto& a : allowed) ok = ok || a == k;
    if (!ok) fail(source, prefix.empty() ? k : prefix + "." + k, "unknown field");
  }
}

}  // namespace

void add_fields(YamlFields& f, TrainerParams& p) {
  f.add("mode", &p.mode, "hierarchical (the DQN picks the chain) | fixed (a chain of fixed_modules, no DQN)");
  f.add("fixed_modules", &p.fixed_modules, kMinModules, kMaxModules, "chain length of the fixed baseline");
  f.add("motion_algo", &p.motion_algo, "the motion learner: a registered learner of continuous actions (td3, sac)");
  f.add("seed", &p.seed, 0, kMaxSeed, "seeds the learners, the trainer's RNG and the training scenes");
  f.add("warmup_episodes", &p.warmup_episodes, 0, kMaxEpisodes,
        "episodes before learning acts (random actions, or the pilot: warmup_policy)");
  f.add("episodes", &p.episodes, 0, kMaxEpisodes, "training episodes after the warm-up");
  f.add("sync_interval", &p.sync_interval, 1, 100000,
        "control steps between hand-overs of transitions to the learner thread");
  f.add("learner_thread", &p.learner_thread, "run the motion updates on a second thread (same results as inline)");
  f.add("torch_threads", &p.torch_threads, 1, 64, "torch intra-op threads per thread");
  f.add("simulation_threads", &p.simulation_threads, 1, 64,
        "actor threads simulating episodes for the one learner (a seed repeats its numbers for a given count; under "
        "mpirun the other ranks are the actors)");
  f.add("motion_image", &p.motion_image, "the motion model sees the depth image (CNN) beside the state");
  f.add("config_vector", &p.config_vector, "the DQN sees [C_n / 10, scene one-hot] beside its image");
  f.add("config_target_distance", &p.config_target_distance,
        "the DQN also sees module 1's distance to the target (m / 10) after config_vector's values");
  f.add("motion_clearance", &p.motion_clearance,
        "the motion model sees the clearance row (nearest depth per column, or the obstacle scan)");
  f.add("motion_heads_per_chain", &p.motion_heads_per_chain,
        "the motion actor has one output head per chain length (2..10), chosen by a one-hot of the length appended "
        "to its vector (TD3 only)");
  f.add("normalize_state", &p.normalize_state, "scale the state's fields to about [-1, 1]");
  f.add("decision_camera", &p.decision_camera, "the DQN sees the decision camera (env.robot.decision_*)");
  f.add("decision_image_first_only", &p.decision_image_first_only,
        "the DQN sees its image only at the first decision; later ones see a blank image (needs config_vector)");
  f.add("warmup_policy", &p.warmup_policy,
        "who drives the warm-up: random (uniform actions, the paper) | scripted (the pilot, plus noise)");
  f.add("warmup_noise", &p.warmup_noise, 0.0, 2.0, "std of the noise on the pilot's actions, action units");
  f.add("scripted_interval", &p.scripted_interval, 0, kMaxEpisodes,
        "after the warm-up, every this-many-th episode is the pilot's too; 0 = none");
  f.add("pilot_random_configs", &p.pilot_random_configs,
        "those pilot episodes draw their chains uniformly instead of asking the DQN");
  f.add("random_config_interval", &p.random_config_interval, 0, kMaxEpisodes,
        "after the warm-up, every this-many-th model-driven episode draws its chains uniformly instead of asking "
        "the DQN (no pilot needed); 0 = none");
  f.add("stair_curriculum", &p.stair_curriculum, 0.0, 1.0,
        "share of the training episodes after the warm-up whose stair height is drawn in proportion to the run's "
        "recent failure rate at each height (the rest uniformly); 0 = none");
  f.add("stair_curriculum_window", &p.stair_curriculum_window, 1, kMaxEpisodes,
        "the last this-many training episodes at each height give its failure rate (stair_curriculum)");
  f.add("chain_curriculum", &p.chain_curriculum, 0.0, 1.0,
        "share of the training episodes after the warm-up that play a (stair height, first chain) pair drawn in "
        "proportion to p (1 - p), p the pair's recent share of climbed stairs (the rest: the DQN's choice); 0 = none");
  f.add("chain_curriculum_window", &p.chain_curriculum_window, 1, kMaxEpisodes,
        "the last this-many training episodes of each (height, first chain) pair give its p (chain_curriculum)");
  f.add("config_energy_weight", &p.config_energy_weight, -1.0, 10.0,
        "per J; R2's energy weight sigma3 in the returns the DQN learns from before the refit; negative = "
        "env.task.r2.sigma3 (the refit, logs and F(H) keep the task's)");
  f.add("pilot_gait_per_modules", &p.pilot_gait_per_modules,
        "the pilot climbs with each chain length's searched gait (else one gait for all)");
  f.add("pilot_flat_steering", &p.pilot_flat_steering,
        "how the pilot steers on the flat area: planned (on the true layout) | scan (by the obstacle scan)");
  f.add("pilot_stair_steering", &p.pilot_stair_steering,
        "how the pilot steers while climbing: straight | scan (around obstacles on the treads)");
  f.add("pilot_labels", &p.pilot_labels,
        "every transition carries the pilot's action as behaviour-cloning target (td3.bc_weight)");
  f.add("motion_n_step", &p.motion_n_step, 1, 1000, "n of the motion transitions' n-step returns; 1 = one-step TD");
  f.add("greedy_motion_interval", &p.greedy_motion_interval, 0, kMaxEpisodes,
        "every this-many-th model-driven episode is played without exploration noise; 0 = none");
  f.add("config_learns_from", &p.config_learns_from,
        "the episodes whose decisions the DQN learns from: all | model (not the pilot's) | greedy");
  f.add("config_target", &p.config_target,
        "the DQN's target: bootstrap (Eq. 3) | return (the R2 of the rest of the episode)");
  f.add("config_refit_episodes", &p.config_refit_episodes, 0, kMaxEpisodes,
        "then this many episodes in which a fresh DQN (dqn_refit:) learns on the frozen greedy motion model");
  f.add("refit_sweep_scenes", &p.refit_sweep_scenes, 0, kMaxEpisodes,
        "the refit's first this-many x 9 episodes play each scene once per chain length, the first configuration "
        "forced in turn (every chain on the same scenes); 0 = none");
  f.add("refit_motion_from", &p.refit_motion_from,
        "a trained run whose motion model this run takes, frozen, to do only a refit (warm-up and episodes 0)");
  f.add("keep_best_motion", &p.keep_best_motion,
        "the refit freezes (and the run ends with) the motion model of the periodic evaluation with the highest "
        "success (ties: higher F(H)) up to the refit's start, not the last one");
  f.add("motion_average_episodes", &p.motion_average_episodes, 0, kMaxEpisodes,
        "> 0: the refit freezes (and the run ends with) the mean of the motion model's networks taken every "
        "motion_average_interval episodes over the last this-many training episodes and at the refit's start; "
        "0 = the last model");
  f.add("motion_average_interval", &p.motion_average_interval, 1, kMaxEpisodes,
        "training episodes between the snapshots of trainer.motion_average_episodes");
  f.add("scene_source", &p.scene_source,
        "where scene labels come from: ground_truth (the simulator) | classifier (ResNet-18 on depth)");
  f.add("classifier_dir", &p.classifier_dir, "directory of a trained classifier (scene_source: classifier)");
  f.add("scenario", &p.scenario, "the training scenes: a scenario of task::kScenarios");
  f.add("stair_height", &p.stair_height, 0, 0.5,
        "m; 0 = drawn per episode from env.scene.stair_height_a/b/c, > 0 = this height always");
  f.add("eval_interval", &p.eval_interval, 0, kMaxEpisodes,
        "training episodes between periodic greedy evaluations; 0 = none");
  f.add("eval_episodes", &p.eval_episodes, 1, 100000, "episodes per periodic evaluation (heights in turn)");
  f.add("eval_seed", &p.eval_seed, 0, kMaxSeed, "periodic evaluation episode i has seed eval_seed + i");
  f.add("checkpoint_interval", &p.checkpoint_interval, 1, kMaxEpisodes,
        "training episodes between checkpoints (and at the end, and on Ctrl-C)");
  f.add("progress_interval", &p.progress_interval, 1, kMaxEpisodes, "training episodes between progress lines");
  f.add("env_dir", &p.env_dir, "directory of robot/scene/motion/task.yaml; empty = configs/sim");
}

void add_fields(YamlFields& f, EvalParams& p) {
  f.add("episodes", &p.episodes, 1, 1000000, "greedy episodes of `comorph eval` (stair heights in turn)");
  f.add("seed", &p.seed, 0, kMaxSeed, "episode i has seed seed + i");
  f.add("workers", &p.workers, 0, 256, "threads, each with its own env and networks; 0 = one per core");
}

namespace {

TrainerParams read_trainer(const YAML::Node& n, const std::string& source) {
  TrainerParams p;
  const std::string pre = "trainer";
  YamlFields f(source);
  f.set_prefix(pre + ".");
  add_fields(f, p);
  f.apply(n, pre + ".");
  if (!rl::has_learner(p.motion_algo) || rl::learner_entry(p.motion_algo).actions != rl::ActionKind::kContinuous) {
    std::string names;
    for (const std::string& n : rl::learner_names())
      if (rl::learner_entry(n).actions == rl::ActionKind::kContinuous) names += (names.empty() ? "" : " | ") + n;
    fail(source, pre + ".motion_algo", "'" + quote_value(p.motion_algo) + "' is not one of " + names +
                                           " (the registered learners of continuous actions)");
  }
  if (p.motion_heads_per_chain && p.motion_algo != "td3")
    fail(source, pre + ".motion_heads_per_chain", "actor heads per chain length need trainer.motion_algo td3, not '" +
                                                      quote_value(p.motion_algo) + "'");
  if (p.config_learns_from == ConfigLearnsFrom::greedy && p.greedy_motion_interval < 1)
    fail(source, pre + ".config_learns_from", "greedy needs trainer.greedy_motion_interval >= 1");
  if (p.decision_image_first_only && !p.config_vector)
    fail(source, pre + ".decision_image_first_only",
         "needs trainer.config_vector true (a later decision would see nothing but a blank image)");
  if (p.config_target_distance && !p.config_vector)
    fail(source, pre + ".config_target_distance", "needs trainer.config_vector true (the distance follows its values)");
  if (!p.refit_motion_from.empty()) {
    if (p.warmup_episodes != 0 || p.episodes != 0 || p.config_refit_episodes < 1)
      fail(source, pre + ".refit_motion_from",
           "a refit of another run's motion model needs trainer.warmup_episodes 0, trainer.episodes 0 and "
           "trainer.config_refit_episodes >= 1");
  } else if (p.warmup_episodes + p.episodes < 1) {
    // A run without a single episode would end at once with no checkpoint to resume or evaluate.
    fail(source, pre + ".episodes", "warmup_episodes + episodes must be at least 1");
  }
  if (p.keep_best_motion && (p.config_refit_episodes < 1 || p.episodes < 1 || p.eval_interval < 1))
    fail(source, pre + ".keep_best_motion",
         "needs training episodes (trainer.episodes >= 1), periodic evaluations (trainer.eval_interval >= 1) and a "
         "refit that takes the best one (trainer.config_refit_episodes >= 1)");
  if (p.motion_average_episodes > 0) {
    if (p.keep_best_motion)
      fail(source, pre + ".motion_average_episodes",
           "cannot be used with trainer.keep_best_motion (the refit freezes one motion model: the mean or the best)");
    if (p.config_refit_episodes < 1 || p.motion_average_episodes > p.episodes)
      fail(source, pre + ".motion_average_episodes",
           std::to_string(p.motion_average_episodes) + " needs at least as many training episodes (trainer.episodes: " +
               std::to_string(p.episodes) + ") and a refit that takes the mean (trainer.config_refit_episodes >= 1)");
  }
  if (p.refit_sweep_scenes * kCandidates > p.config_refit_episodes)
    fail(source, pre + ".refit_sweep_scenes",
         std::to_string(p.refit_sweep_scenes) + " scenes x " + std::to_string(kCandidates) +
             " chain lengths is more than trainer.config_refit_episodes (" + std::to_string(p.config_refit_episodes) +
             ")");
  if (p.stair_curriculum > 0 && p.stair_height > 0)
    fail(source, pre + ".stair_curriculum",
         "needs the stair heights drawn per episode (trainer.stair_height 0), not one height always");
  if (p.chain_curriculum > 0 && p.mode != TrainerMode::hierarchical)
    fail(source, pre + ".chain_curriculum", "needs trainer.mode hierarchical (a fixed chain has no first choice to draw)");
  if (p.config_refit_episodes > 0 && p.mode != TrainerMode::hierarchical)
    fail(source, pre + ".config_refit_episodes", "needs trainer.mode hierarchical (a fixed chain has no DQN)");
  // Whether the directory holds a classifier is checked where it is loaded
  // (SceneSource): a config's settings read the same on any machine.
  if (p.scene_source == SceneSourceKind::classifier && p.classifier_dir.empty())
    fail(source, pre + ".classifier_dir", "scene_source: classifier needs the directory of a trained classifier");
  return p;
}

EvalParams read_eval(const YAML::Node& n, const std::string& source) {
  EvalParams p;
  YamlFields f(source);
  f.set_prefix("eval.");
  add_fields(f, p);
  f.apply(n, "eval.");
  return p;
}

// Applies `node` (null: nothing) to `params` through its field list, then its checks.
template <class Params>
void apply_section(const YAML::Node& node, const std::string& source, Params& params) {
  YamlFields f(source);
  add_fields(f, params);
  f.apply(node);
  if constexpr (std::is_same_v<Params, sim::RobotParams> || std::is_same_v<Params, sim::SceneParams>)
    check_fields(f, params);
}

task::EnvConfig read_env(const YAML::Node& n, const std::string& source, const std::string& env_dir) {
  task::EnvConfig c = task::load_env_config(env_dir);
  check_keys(n, source, "env", {"robot", "scene", "motion", "task"});
  if (!n || n.IsNull()) return c;
  apply_section(n["robot"], source + ": env.robot", c.robot);
  apply_section(n["scene"], source + ": env.scene", c.scene);
  apply_section(n["motion"], source + ": env.motion", c.motion);
  apply_section(n["task"], source + ": env.task", c.task);
  return c;
}

// The sections a config file may have beside the learners' (one per registered learner).
const std::vector<std::string>& fixed_sections() {
  static const std::vector<std::string> names{"trainer", "env", "perception", "dqn_refit", "eval"};
  return names;
}

// The typed config of learner section `name` in `c` (td3, sac, dqn; another
// registered learner's from other_learners, else its defaults).
std::any learner_config(const CooptConfig& c, const std::string& name) {
  if (name == "td3") return c.td3;
  if (name == "sac") return c.sac;
  if (name == "dqn") return c.dqn;
  if (const auto it = c.other_learners.find(name); it != c.other_learners.end()) return it->second;
  return rl::learner_entry(name).default_config();
}

// Binds the settings of `sections` of `c` into `f`, each under its section's
// name. Learner configs are bound through copies kept in `learners`.
void add_sections(YamlFields& f, CooptConfig& c, const std::vector<std::string>& sections,
                  std::vector<std::any>& learners) {
  learners.reserve(sections.size());  // the bound copies must not move
  for (const std::string& section : sections) {
    f.set_prefix(section + ".");
    if (section == "trainer") add_fields(f, c.trainer);
    else if (section == "eval") add_fields(f, c.eval);
    else if (section == "env.robot") sim::add_fields(f, c.env.robot);
    else if (section == "env.scene") sim::add_fields(f, c.env.scene);
    else if (section == "env.motion") control::add_fields(f, c.env.motion);
    else if (section == "env.task") task::add_fields(f, c.env.task);
    else if (section == "perception") perception::add_fields(f, c.perception);
    else if (section == "dqn_refit") rl::add_fields(f, c.dqn_refit);
    else rl::learner_entry(section).add_fields(f, learners.emplace_back(learner_config(c, section)));
  }
}

// The sections a run uses, in the order its config.yaml lists them.
std::vector<std::string> run_sections(const CooptConfig& c) {
  std::vector<std::string> sections{"trainer", "env.robot", "env.scene", "env.motion", "env.task", "perception",
                                    c.trainer.motion_algo};
  if (c.trainer.mode == TrainerMode::hierarchical) sections.push_back("dqn");
  if (c.trainer.mode == TrainerMode::hierarchical && c.trainer.config_refit_episodes > 0)
    sections.push_back("dqn_refit");
  sections.push_back("eval");
  return sections;
}

// Every setting of the run, defaults included, as YAML text.
std::string resolved_text(const CooptConfig& config) {
  CooptConfig c = config;
  std::vector<std::any> learners;
  YamlFields f("");
  add_sections(f, c, run_sections(c), learners);
  YAML::Emitter e;
  e << f.values();
  return e.c_str();
}

// Deep merge: `over`'s keys replace or, for mappings on both sides, merge into `base`'s.
void merge_into(YAML::Node base, const YAML::Node& over) {
  for (const auto& item : over) {
    const std::string key = item.first.Scalar();
    YAML::Node target = base[key];
    if (target.IsMap() && item.second.IsMap())
      merge_into(target, item.second);
    else
      base[key] = item.second;
  }
}

CooptConfig config_from_tree(YAML::Node root, const std::string& source, const std::vector<std::string>& sets);

// The YAML tree of a config file: its own keys over those of its `base:`
// preset (a path relative to the file's directory), which must be a valid
// config on its own. `depth` stops a preset that builds on itself.
YAML::Node preset_tree(const std::string& text, const std::string& source, int depth) {
  YAML::Node root = parse_yaml(text, source);  // also refuses a key given twice
  if (!root || root.IsNull())
    throw std::runtime_error(source + ": empty config (expected the sections trainer, env, perception, eval and "
                                      "the learners', or base: PRESET)");
  if (!root.IsMap()) throw std::runtime_error(source + ": expected a mapping of sections" + line_of(root));
  const YAML::Node base = root["base"];
  if (!base) return root;
  if (!base.IsScalar() || base.Scalar().empty()) fail(source, "base", "expected a preset file name" + line_of(base));
  if (depth >= 8) fail(source, "base", "more than 8 presets deep (a preset that builds on itself?)");
  const std::string base_path = (std::filesystem::path(source).parent_path() / base.Scalar()).string();
  if (!std::filesystem::is_regular_file(base_path))
    fail(source, "base", "no preset '" + quote_value(base_path) + "'" + line_of(base));
  YAML::Node merged = preset_tree(read_text_file(base_path), base_path, depth + 1);
  config_from_tree(YAML::Clone(merged), base_path, {});  // a fault of the base is refused under its own name
  root.remove("base");
  merge_into(merged, root);
  return merged;
}

// The config of a file's tree (preset_tree) with `sets` applied.
CooptConfig config_from_tree(YAML::Node root, const std::string& source, const std::vector<std::string>& sets) {
  for (const auto& s : sets) apply_set(root, s);
  const std::string src = sets.empty() ? source : source + " (with --set)";
  std::vector<std::string> sections = fixed_sections();
  for (const std::string& name : rl::learner_names()) sections.push_back(name);
  check_keys(root, src, "", sections);

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
  const auto given = [&](const std::string& name) { return root[name] && !root[name].IsNull(); };
  const auto require_section = [&](const std::string& name, const std::string& needed_by, const std::string& what) {
    if (!given(name))
      throw std::runtime_error(src + ": no '" + name + ":' section: " + needed_by + " needs the " + what +
                               "'s hyperparameters there (configs/quick.yaml has them)");
  };
  if (c.trainer.motion_algo == "td3" || c.trainer.motion_algo == "sac")  // the typed sections; others: their defaults
    require_section(c.trainer.motion_algo, "trainer.motion_algo " + c.trainer.motion_algo, "motion model");
  if (c.trainer.mode == TrainerMode::hierarchical) require_section("dqn", "trainer.mode hierarchical", "configuration model");
  c.td3 = rl::Td3Config::from_yaml(root["td3"], src + ": td3");
  c.sac = rl::SacConfig::from_yaml(root["sac"], src + ": sac");
  c.dqn = rl::DqnConfig::from_yaml(root["dqn"], src + ": dqn");
  for (const std::string& name : rl::learner_names())
    if (name != "td3" && name != "sac" && name != "dqn" && given(name))
      c.other_learners[name] = rl::learner_entry(name).read_config(root[name], src + ": " + name);
  c.dqn_refit = c.dqn;
  if (given("dqn_refit")) {  // checked also where no DQN is refitted (a preset's fixed columns)
    YAML::Node merged = given("dqn") ? YAML::Clone(root["dqn"]) : YAML::Node(YAML::NodeType::Map);
    if (!root["dqn_refit"].IsMap())
      throw std::runtime_error(src + ": dqn_refit: expected a mapping of dqn keys" + line_of(root["dqn_refit"]));
    for (const auto& kv : root["dqn_refit"]) merged[kv.first.Scalar()] = kv.second;
    c.dqn_refit = rl::DqnConfig::from_yaml(merged, src + ": dqn_refit (over dqn)");
  }
  if (given("td3") && (c.td3.random_action_episodes != 0 || c.td3.random_action_steps != 0))
    throw std::runtime_error(src + ": field 'td3.random_action_episodes/steps': must be 0, "
                                   "the warm-up is trainer.warmup_episodes (both models)");
  if (given("sac") && (c.sac.random_action_episodes != 0 || c.sac.random_action_steps != 0))
    throw std::runtime_error(src + ": field 'sac.random_action_episodes/steps': must be 0, "
                                   "the warm-up is trainer.warmup_episodes (both models)");
  c.text = resolved_text(c);
  c.preset = std::filesystem::path(source).stem().string();
  return c;
}

}  // namespace

CooptConfig coopt_config_from_text(const std::string& text, const std::string& source,
                                   const std::vector<std::string>& sets) {
  return config_from_tree(preset_tree(text, source, 0), source, sets);
}

CooptConfig load_coopt_config(const std::string& path, const std::vector<std::string>& sets) {
  return coopt_config_from_text(read_text_file(path), path, sets);
}

std::string config_identity(const std::string& path) {
  YAML::Node resolved = YAML::Load(load_coopt_config(path).text);
  resolved["trainer"].remove("seed");
  return YAML::Dump(resolved);
}

std::vector<double> stair_heights(const CooptConfig& config) {
  if (config.trainer.stair_height > 0) return {config.trainer.stair_height};
  const auto drawn = config.env.scene.stair_heights();
  std::vector<double> heights(drawn.begin(), drawn.end());
  std::sort(heights.begin(), heights.end());
  heights.erase(std::unique(heights.begin(), heights.end()), heights.end());
  return heights;
}

std::vector<SettingsSection> settings_sections(const CooptConfig& config) {
  struct About {
    std::string section, about;
  };
  std::vector<About> abouts{
      {"trainer", "The hierarchical trainer: budget, schedules, threads, the pilot, the scene source."},
      {"env.robot", "The simulated module and its sensors (over configs/sim/robot.yaml)."},
      {"env.scene", "The scenario's stairs, obstacles and target (over configs/sim/scene.yaml)."},
      {"env.motion", "The motion modes: the 5-D action to wheel speeds and hinge targets (over configs/sim/motion.yaml)."},
      {"env.task", "Rewards R1 and R2, the objective F(H), termination (over configs/sim/task.yaml)."},
      {"perception", "The scene classifier, its training and the switch detector."}};
  for (const std::string& name : rl::learner_names())
    abouts.push_back({name, "Hyperparameters of the " + name + " learner (" +
                                (rl::learner_entry(name).actions == rl::ActionKind::kDiscrete
                                     ? "discrete actions: the configuration model; dqn_refit: takes any of these "
                                       "keys for the refit DQN"
                                     : "continuous actions: a motion model, trainer.motion_algo") +
                                ")."});
  abouts.push_back({"eval", "Defaults of `comorph eval`."});
  CooptConfig c = config;
  std::vector<SettingsSection> list;
  for (const About& a : abouts) {
    std::vector<std::any> learners;
    YamlFields f("");
    add_sections(f, c, {a.section}, learners);
    list.push_back({a.section, a.about, f.settings()});
  }
  return list;
}

CooptConfig default_coopt_config() {
  CooptConfig c;
  c.env = task::load_env_config(resource_path("configs/sim"));
  c.env_dir = resource_path("configs/sim");
  c.text = resolved_text(c);
  return c;
}

}  // namespace comorph::coopt
