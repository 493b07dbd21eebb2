// One episode of the hierarchical co-optimization, for every caller: a
// training episode (with learning hooks), a periodic or final greedy
// evaluation episode, a rendered one (with a StepObserver). The runner owns
// what an episode needs besides the models: the env, the scene source and
// the observation buffers, allocated once (no allocation in the step loop).
// Internal to coopt (torch types); the CLI sees coopt/trainer.hpp only.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "coopt/config.hpp"
#include "coopt/trainer.hpp"
#include "perception/switch_detector.hpp"
#include "rl/env.hpp"
#include "rl/learner.hpp"
#include "rl/n_step.hpp"
#include "rl/policy.hpp"
#include "task/multitask_env.hpp"
#include "task/scripted_pilot.hpp"

namespace comorph::perception {
class SceneClassifier;
class SceneMonitor;
}  // namespace comorph::perception

namespace comorph::coopt {

using Clock = std::chrono::steady_clock;

// Where an actor's (or the host's) time goes (TrainerTiming): each lap() gives the
// time since the previous one to a phase, so every moment counts once. One
// steady_clock read a lap and fixed storage: cheap enough for every control
// step (~20 ns against a step of ~0.3 ms), and it never touches the results.
enum Phase {
  kEnvStep, kEnvReset, kActing, kHandover, kWaiting, kMotionUpdates, kDqn, kClassifier,
  kEvaluation, kCheckpoint, kLogging, kOther, kPhases
};
struct Laps {
  bool on = false;  // only inside Trainer::run()
  Clock::time_point last;
  std::array<Clock::duration, kPhases> spent{};
  void start() {
    on = true;
    last = Clock::now();
  }
  void lap(Phase p) {
    if (!on) return;
    const Clock::time_point now = Clock::now();
    spent[p] += now - last;
    last = now;
  }
};

// The discount of the motion learner's config (td3: or sac:; 0.99 for others).
double motion_gamma(const CooptConfig& c);

// The inputs of the two models.
rl::ObservationSpec motion_spec(const CooptConfig& c);
rl::ObservationSpec config_spec(const CooptConfig& c);

// The motion model's input from the env's observation (depth(), state(),
// clearance()): the image if asked, the state (scaled if asked), then the
// clearance row if asked.
void fill_motion(const float* depth, const float* state, const float* clearance, const TrainerParams& t,
                 rl::Observation& o);
// The configuration model's vector [C_n / 10, scene one-hot] (then the
// distance to the target / 10 m with trainer.config_target_distance; it must
// be >= 0 then) and mask (the current configuration and those it can shed
// modules to; `mask` is its storage); the image is already in o.image.
void fill_config_vector(const TrainerParams& t, const Configuration& current, int scene, double target_distance_m,
                        std::vector<std::uint8_t>& mask, rl::Observation& o);
// The configuration model's whole observation of `env`: its image (the
// decision camera's with trainer.decision_camera, else depth(); blank at every
// decision but the episode's `first` with trainer.decision_image_first_only),
// then fill_config_vector's.
void fill_config(const task::MultiTaskEnv& env, const TrainerParams& t, int scene, bool first,
                 std::vector<std::uint8_t>& mask, rl::Observation& o);

// The scene spec of evaluation episode i (heights cycle 0.04, 0.06, 0.08).
task::EpisodeSpec eval_spec(const CooptConfig& c, const task::ScenarioSpec& scenario, std::uint64_t seed, int i);

// Scene source: the switch detector on ground-truth labels or on the classifier.
class SceneSource {
 public:
  explicit SceneSource(const CooptConfig& c);
  ~SceneSource();
  std::function<int(int, int)> label_source;  // optional relabelling of the ground truth

  void reset(const task::MultiTaskEnv& env);
  perception::SwitchDecision step(const task::MultiTaskEnv& env);
  int current() const;

 private:
  int label(const task::MultiTaskEnv& env) const {
    return label_source ? label_source(step_, env.scene_label()) : env.scene_label();
  }
  int step_ = 0;  // control steps since reset
  perception::SwitchDetectorParams params_;
  perception::SwitchDetector detector_;
  std::unique_ptr<perception::SceneClassifier> classifier_;
  std::unique_ptr<perception::SceneMonitor> monitor_;
};

// What acts in an episode: acting copies (rl::Policy) of both models; their
// learners live with the learner host (coopt/learner_host.hpp).
struct Agent {
  std::unique_ptr<rl::Policy> motion;  // the motion model
  std::unique_ptr<rl::Policy> config;  // the configuration model (DQN); nullptr in fixed mode
  bool hierarchical() const { return config != nullptr; }
};

// Training hooks of one episode (absent for evaluation).
struct LearnHooks {
  // A motion transition to learn from: obs, action, return, next obs,
  // terminated, truncated, and the control steps it sums (trainer.motion_n_step:
  // it leaves up to n - 1 steps after its own, all of them at the episode's end).
  std::function<void(const rl::Observation&, const rl::Action&, float, const rl::Observation&, bool, bool, int)>
      motion;
  // Every control step, after `motion`: whether the episode ended with it.
  std::function<void(bool)> stepped;
  std::function<void(const rl::Observation&, const rl::Action&, float, const rl::Observation&, bool, bool, int)>
      config;
  // The R2 that `config` is paid (trainer.config_energy_weight); null: env.task.r2.
  const task::R2Params* config_r2 = nullptr;
  std::function<int(const std::vector<std::uint8_t>&)> random_config;  // warm-up choice, -1 = ask the DQN
  // The scripted pilot, when set, plans every episode and gives each step's
  // action as the transition's behaviour-cloning target (Action::target); with
  // pilot_drives it also drives (its action + Gaussian noise of std pilot_noise
  // from pilot_rng) instead of the motion model.
  task::ScriptedPilot* pilot = nullptr;
  bool pilot_drives = false;
  double pilot_noise = 0;
  std::mt19937_64* pilot_rng = nullptr;
  bool motion_greedy = false;  // the motion model acts without exploration noise
  Laps* laps = nullptr;  // the trainer's timing (TrainerTiming)
};

// The scripted pilot as trainer.pilot_* set it: its stair gaits and steering.
void configure_pilot(const TrainerParams& t, task::ScriptedPilot& pilot);

// Reusable buffers of an episode (no allocation in the step loop).
struct Buffers {
  rl::Observation obs, next, cobs, cnext;
  rl::Action action, caction;
  std::vector<std::uint8_t> mask;
};
void allocate_buffers(const CooptConfig& c, Buffers& b);

class EpisodeRunner {
 public:
  // `label_source`: TrainerCallbacks::label_source (may be empty).
  EpisodeRunner(const CooptConfig& config, std::function<int(int, int)> label_source = {});
  // One episode; learning when `hooks` is given. The env is reset here.
  // `observe` (may be null) sees the env after the reset that starts control
  // and after every step.
  EpisodeLog play(Agent& agent, task::EpisodeSpec spec, bool explore, const LearnHooks* hooks = nullptr,
                  const StepObserver* observe = nullptr);
  const task::MultiTaskEnv& env() const { return env_; }

 private:
  const CooptConfig& config_;
  task::MultiTaskEnv env_;
  SceneSource scene_;
  Buffers b_;
  rl::NStepReturns n_step_;  // the motion transitions' returns (trainer.motion_n_step)
};

}  // namespace comorph::coopt
