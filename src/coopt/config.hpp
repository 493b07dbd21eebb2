// One run of the hierarchical co-optimization = one YAML file (configs/paper.yaml,
// quick.yaml, ci.yaml) with these sections, every key optional:
//
//   base:       a preset this file builds on (path relative to the file): its
//               keys apply first, this file's over them
//   trainer:    TrainerParams below (episodes, schedules, threads, scene source, ...)
//   td3:        rl::Td3Config fields   (motion model, trainer.motion_algo: td3)
//   sac:        rl::SacConfig fields   (motion model, trainer.motion_algo: sac)
//   dqn:        rl::DqnConfig fields   (configuration model)
//   <learner>:  the fields of any other learner in rl's registry
//   dqn_refit:  rl::DqnConfig fields that differ for the refit DQN
//               (trainer.config_refit_episodes); the rest are dqn:'s
//   env:        {robot, scene, motion, task}: overrides of configs/sim/*.yaml
//   perception: {classifier, training, switch_detector} (configs/perception.yaml layout)
//   eval:       EvalParams below
//
// Each section's fields are declared once, with range and meaning, by an
// add_fields(YamlFields&, Struct&) next to its struct: the reader, `comorph
// config keys`, docs/config.md and the resolved text below all use them.
// `--set a.b.c=value` overrides any key (value parsed as YAML, so lists work).
// Unknown keys and out-of-range values throw std::runtime_error naming the
// source, the dotted key and the line. No torch in this header: the CLI includes it.
#pragma once

#include <any>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "common/enum_names.hpp"
#include "common/yaml_fields.hpp"  // Setting
#include "perception/perception_config.hpp"
#include "rl/learner_params.hpp"
#include "task/env_config.hpp"
#include "task/pilot_params.hpp"
#include "task/scenario.hpp"

namespace comorph::coopt {

// The trainer's choices (TrainerParams says what each means) and their names.
enum class TrainerMode { hierarchical, fixed };
enum class WarmupPolicy { random, scripted };
enum class ConfigLearnsFrom { all, model, greedy };
enum class ConfigTarget { bootstrap, episode_return };    // "return" is a C++ keyword
enum class SceneSourceKind { ground_truth, classifier };  // (SceneSource gives the labels)
constexpr auto enum_names(TrainerMode) {
  return std::array{EnumName{TrainerMode::hierarchical, "hierarchical"}, EnumName{TrainerMode::fixed, "fixed"}};
}
constexpr auto enum_names(WarmupPolicy) {
  return std::array{EnumName{WarmupPolicy::random, "random"}, EnumName{WarmupPolicy::scripted, "scripted"}};
}
constexpr auto enum_names(ConfigLearnsFrom) {
  return std::array{EnumName{ConfigLearnsFrom::all, "all"}, EnumName{ConfigLearnsFrom::model, "model"},
                    EnumName{ConfigLearnsFrom::greedy, "greedy"}};
}
constexpr auto enum_names(ConfigTarget) {
  return std::array{EnumName{ConfigTarget::bootstrap, "bootstrap"}, EnumName{ConfigTarget::episode_return, "return"}};
}
constexpr auto enum_names(SceneSourceKind) {
  return std::array{EnumName{SceneSourceKind::ground_truth, "ground_truth"},
                    EnumName{SceneSourceKind::classifier, "classifier"}};
}

struct TrainerParams {
  TrainerMode mode = TrainerMode::hierarchical;  // hierarchical (DQN picks the chain) | fixed (fixed_modules, no DQN)
  int fixed_modules = 4;              // chain length of the fixed baseline, 2..10
  // Motion learner: a name in rl's learner registry (td3 | sac, or one a
  // program registers), so it stays a string.
  std::string motion_algo = "td3";
  int seed = 1;                       // seeds learners, trainer RNG and the training scenes
  int warmup_episodes = 300;          // episodes of uniform random actions (both models) before learning acts
  int episodes = 4000;                // training episodes after the warm-up
  // Motion-model updates run on a learner thread, overlapped with the
  // simulation: every `sync_interval` control steps (and at every episode end)
  // the actor hands its transitions over, waits for the previous batch of
  // updates and takes the new actor weights (coopt/acting.hpp). The schedule
  // does not depend on timing, so both thread modes give identical results.
  int sync_interval = 64;             // control steps between hand-overs (the acting policy lags by <= 2 of these)
  bool learner_thread = true;         // false: run the updates inline (one core, same results)
  int torch_threads = 1;              // torch intra-op threads per thread (1: small nets, reproducible)
  // Actors on threads, each with its own env, scene source, pilot and acting
  // copies of both models, feeding the one learner host (coopt/acting.hpp;
  // under mpirun the job's other ranks are the actors instead).
  // 1: the single actor above. N > 1: they step in rounds of equal
  // simulation work (sync_interval control steps of a 4-module chain; a
  // thread whose episode ends waits for the round's end), the round's
  // transitions and decisions go to the learner thread in thread order,
  // and every episode draws from its own random streams; so a (seed, N) pair
  // gives the same results every time, but not those of another N.
  int simulation_threads = 1;
  bool motion_image = true;           // the motion model sees the depth image (CNN) + state; false: state only
  bool motion_clearance = false;      // the motion model also sees task's clearance(): nearest depth per image column
  // The motion model's actor has one output head per chain length (2..10
  // modules; the hidden layers shared), chosen by a one-hot of the chain's
  // length appended to its vector: each chain's gait learns apart from the
  // others'. TD3 only. The paper's "separate groups of motion parameters".
  bool motion_heads_per_chain = false;
  bool normalize_state = false;       // scale the state vector's fields to about [-1, 1] (fixed factors, trainer.cpp)
  bool config_vector = true;          // the DQN sees [C_n / 10, scene one-hot x3] beside the depth image
  // The DQN also sees how far module 1 still is from the target (m / 10),
  // appended to config_vector's. A bootstrapped target (config_target
  // bootstrap) can then value what is left of the course after the stairs: a
  // longer chain ends the stairs segment farther along, and the image does not
  // show it. The distance says nothing of the stair height or the obstacles.
  bool config_target_distance = false;
  bool decision_camera = false;       // the DQN sees the decision camera (env.robot.decision_*), not the motion camera
  // The DQN sees its image only at the episode's first decision; later ones
  // (after a scene switch) see a blank image, so that choice rests on
  // config_vector's chain and scene. What the camera shows while the robot
  // drives changes from step to step, and a choice that followed it flickered.
  bool decision_image_first_only = false;
  // Who drives the motion during the warm-up: "random" (uniform actions, the
  // paper) or "scripted" (task::ScriptedPilot, which plans on the true obstacle
  // layout, plus Gaussian noise): demonstrations in the replay, marked as such.
  // The models never see what the pilot knows; they learn from its transitions.
  WarmupPolicy warmup_policy = WarmupPolicy::random;
  double warmup_noise = 0.2;          // std of the noise on the pilot's actions (action units)
  int scripted_interval = 0;          // after the warm-up, every this-many-th episode is the pilot's too (0 = none)
  // Those later pilot episodes choose their configurations uniformly, as the
  // warm-up does, instead of asking the DQN: the motion model keeps seeing
  // demonstrations with every chain length, and the DQN the outcome of each.
  bool pilot_random_configs = false;
  // Every this-many-th model-driven training episode draws its configurations
  // uniformly too (0 = none): the motion model keeps practising every chain
  // length without a pilot, instead of only the one the DQN settles on.
  int random_config_interval = 0;
  // A share of the training episodes after the warm-up (0 = none) takes its
  // stair height in proportion to the run's recent failure rate at each
  // height, over its last stair_curriculum_window training episodes there
  // (coopt/curriculum.hpp); the rest keep the scene's uniform draw.
  // More practice where the run fails, from its own outcomes only.
  double stair_curriculum = 0;
  int stair_curriculum_window = 50;
  // A share of the training episodes after the warm-up (0 = none) plays a
  // (stair height, first chain) pair drawn in proportion to p (1 - p), p the
  // share of the pair's last chain_curriculum_window training episodes whose
  // first chain climbed the stairs (coopt/curriculum.hpp): the motion model
  // practises every chain where it is learning, not only the DQN's choice.
  // Later decisions stay the DQN's. The rest keep the scene's (or the stair
  // curriculum's) height and the DQN's first choice.
  double chain_curriculum = 0;
  int chain_curriculum_window = 20;
  // R2's energy weight (sigma3, per J of stair energy) in the returns the
  // configuration model learns from before the DQN refit; negative = the
  // task's (env.task.r2.sigma3). The refit, the logs and F(H) keep the task's.
  // The DQN that picks the training episodes' chains decides what data the
  // motion model gets; with a heavy weight it prefers a short chain that
  // fails cheaply to a long one that is learning to climb.
  double config_energy_weight = -1;
  // The refit's first refit_sweep_scenes x 9 episodes play each of that many
  // scenes once per chain length, the first configuration forced in turn (the
  // later ones the DQN's). Every (stair height, chain) pair then gets samples
  // in proportion, and the chains' returns share each scene's luck (common
  // random numbers), instead of ~10 epsilon-greedy draws of independent
  // scenes each. 0 = none.
  int refit_sweep_scenes = 0;
  // The pilot climbs with each chain length's own searched gait
  // (task::searched_stair_gaits); false: one gait (a0, a2, a3, a4) = (1, 1, -0.5, 1) for all.
  bool pilot_gait_per_modules = false;
  // How the pilot steers on the flat area (task::FlatSteering): planned (a path
  // on the true obstacle layout) | scan (towards the open direction of the
  // obstacle scan nearest the goal: its labels depend only on what the motion
  // model sees, so the model can follow them; planned labels differ between
  // states the model cannot tell apart, and it dithered in front of obstacles).
  task::FlatSteering pilot_flat_steering = task::FlatSteering::planned;
  // How the pilot steers while climbing (task::StairSteering): straight (up
  // the middle) | scan (around the obstacles the scan shows on the treads:
  // the mixed scenario; short chains turn in stair mode, 5 and more barely).
  task::StairSteering pilot_stair_steering = task::StairSteering::straight;
  // Every this-many-th episode after the warm-up that the motion model drives
  // is played without its exploration noise (its transitions still train it); 0 = none.
  int greedy_motion_interval = 0;
  // The episodes whose decisions the DQN learns from: all | model (those the
  // motion model drove, not the pilot's) | greedy (the greedy-motion ones).
  // Its values are what each chain achieved there, so they should come from
  // the policy that is evaluated: the pilot climbs with chains the model
  // cannot drive yet, and the exploring model with chains the greedy one
  // cannot (3 modules at 0.06 m: 40 of 43 exploring, 0 of 10 greedy).
  ConfigLearnsFrom config_learns_from = ConfigLearnsFrom::all;
  // The DQN's target for a decision: bootstrap (Eq. 3: R2 + gamma max Q(s'))
  // | return (the R2 of this and every later segment of the episode, each
  // later one discounted once more by dqn.gamma, stored as terminal). The
  // return needs no estimate of the state after the stairs, which the decision
  // image cannot tell apart: a longer chain's head is farther along when the
  // stairs segment ends (one module length, 16 of R1, per module) and the rest
  // of the course is shorter by as much, which bootstrapping does not see.
  ConfigTarget config_target = ConfigTarget::bootstrap;
  // After the training episodes, this many more in which the motion model is
  // frozen and greedy and a fresh DQN (the dqn: section with dqn_refit:'s
  // keys over it, its own epsilon schedule) learns from every decision. Its values then describe the final
  // motion model; during training they mix every stage of it, and the early
  // ones stay in its replay. 0 = none.
  int config_refit_episodes = 0;
  // A trained run directory whose motion model (its latest checkpoint's) this
  // run takes, frozen, to do only a refit: warmup_episodes and episodes 0,
  // config_refit_episodes > 0. Another configuration model for a motion model
  // already trained (other refit settings, another R2) without training it
  // again. The run copies the weights into its own checkpoints at its start.
  std::string refit_motion_from;
  // The motion model the refit freezes (and the run ends with) is the one of
  // the periodic evaluation up to the refit's start with the highest success
  // (ties: higher F(H)), not the last: a TD3 policy's quality swings between
  // updates (SB3's EvalCallback keeps its best model the same way). An
  // evaluation is also taken at the refit's start. Its eval_episodes decide
  // how reliable the choice is.
  bool keep_best_motion = false;
  // > 0: the refit freezes (and the run ends with) the mean of the motion
  // model's acting networks taken after every motion_average_interval-th
  // episode over the last this-many training episodes, and at the refit's
  // start: weight averaging (Izmailov et al. 2018; Nikishin et al. 2018 for
  // RL), a steadier model than any one snapshot of a swinging TD3 policy.
  int motion_average_episodes = 0;
  int motion_average_interval = 50;
  // Episode index of the refit's first episode (= warm-up + training episodes).
  int refit_start() const { return warmup_episodes + episodes; }
  // After this many episodes the motion model goes into the mean (trainer.motion_average_episodes).
  bool motion_average_snapshot(int episodes_done) const {
    return motion_average_episodes > 0 && episodes_done <= refit_start() &&
           episodes_done >= refit_start() - motion_average_episodes &&
           (episodes_done % motion_average_interval == 0 || episodes_done == refit_start());
  }
  // A checkpoint after this many episodes holds the refit DQN (built with dqn_refit:), not the training one.
  bool holds_refit_dqn(int episodes_done) const { return episodes_done > refit_start(); }
  int total_episodes() const { return refit_start() + config_refit_episodes; }
  // Every training transition carries the pilot's action for its state as a
  // behaviour-cloning target (td3.bc_weight), also where the motion model drove:
  // the pilot labels the states the learner visits (DAgger, Ross et al. 2011).
  bool pilot_labels = false;
  // The motion transitions an actor hands over carry n-step returns
  // (rl/n_step.hpp): the rewards of this step and the next n - 1, discounted
  // by the motion learner's gamma, then its bootstrap discounted by gamma^n.
  // 1 = one-step TD (the paper).
  int motion_n_step = 1;
  // ground_truth (simulator labels) | classifier (ResNet-18 on depth)
  SceneSourceKind scene_source = SceneSourceKind::ground_truth;
  std::string classifier_dir;         // trained classifier directory (scene_source: classifier)
  task::Scenario scenario = task::Scenario::standard;  // training scene: a row of task::kScenarios ("default")
  double stair_height = 0;            // m; 0 = drawn per episode from {0.04, 0.06, 0.08}; > 0 fixed (reduced tasks)
  int eval_interval = 100;            // training episodes between periodic greedy evaluations (0 = none)
  int eval_episodes = 6;              // episodes per periodic evaluation (heights cycle 0.04, 0.06, 0.08)
  int eval_seed = 900000;             // seed of periodic evaluation episode i is eval_seed + i
  int checkpoint_interval = 10;       // training episodes between checkpoints (and at the end / Ctrl-C)
  int progress_interval = 1;          // training episodes between progress lines on stderr
  std::string env_dir;                // base env configs (robot/scene/motion/task.yaml); "" = <source>/configs/sim
};

// `comorph eval` defaults (the command line overrides them).
struct EvalParams {
  int episodes = 30;     // greedy episodes; stair height of episode i = heights[i % 3]
  int seed = 700000;     // seed of episode i is seed + i
  int workers = 2;       // threads, each with its own env and network copies; 0 = one per core
};

struct CooptConfig {
  TrainerParams trainer;
  EvalParams eval;
  task::EnvConfig env;                         // configs/sim + the env: overrides
  perception::PerceptionConfig perception;     // classifier + switch detector
  // The learners' hyperparameters (the td3:, sac: and dqn: sections; a
  // section the run does not use may be absent and keeps the defaults).
  rl::Td3Config td3;
  rl::SacConfig sac;
  rl::DqnConfig dqn;
  // The refit DQN's (trainer.config_refit_episodes): dqn: with the keys of
  // dqn_refit: over it. Its network is dqn:'s (evaluation loads either model).
  rl::DqnConfig dqn_refit;
  // The sections of the other registered learners the file gives, typed by
  // the registry (rl::LearnerEntry::read_config).
  std::map<std::string, std::any> other_learners;
  // The resolved config: every setting of the sections the run uses, defaults
  // included, as YAML. What the run directory's config.yaml holds, the run's
  // identity (a checkpoint is compared against it) and reads back to itself.
  std::string text;
  // The simulator config files the env was built from (task::env_files_text
  // of env_dir): the other half of a run's identity, compared on resume.
  std::string env_text;
  std::string env_dir;                         // trainer.env_dir, or <source>/configs/sim
  std::string preset;                          // file stem, e.g. "quick"
};

// Every field of TrainerParams / EvalParams with its range and meaning.
void add_fields(YamlFields& f, TrainerParams& p);
void add_fields(YamlFields& f, EvalParams& p);

// Loads `path` (over its base: presets), applies `sets` ("a.b=value"),
// validates every section. An empty file is refused as such.
CooptConfig load_coopt_config(const std::string& path, const std::vector<std::string>& sets = {});
// The same from YAML text (source names it in errors).
CooptConfig coopt_config_from_text(const std::string& text, const std::string& source,
                                   const std::vector<std::string>& sets = {});

// A run's config.yaml resolved (defaults filled in), without trainer.seed:
// equal for runs of the same settings, whether their file was written resolved
// or as the merged input (runs made before configs were resolved).
// report::ConfigIdentity for the reports and `experiment --collect`.
std::string config_identity(const std::string& config_yaml_path);

// The stair heights of the run's episodes, m, ascending: trainer.stair_height
// when it is fixed, else the distinct heights of env.scene. Evaluations and
// their summaries report each.
std::vector<double> stair_heights(const CooptConfig& config);

// A section of a config as `comorph config keys` and docs/config.md list it.
struct SettingsSection {
  std::string name;   // "trainer", "env.robot", "td3", ...
  std::string about;  // one sentence
  std::vector<Setting> settings;  // keys relative to the file's root ("trainer.episodes")
};
// Every section a config may have (every registered learner's too), with
// the values of `config`.
std::vector<SettingsSection> settings_sections(const CooptConfig& config);
// The defaults: no file, env from configs/sim, each learner's defaults.
CooptConfig default_coopt_config();

}  // namespace comorph::coopt
