#include "coopt/episode_runner.hpp"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "coopt/segment.hpp"
#include "perception/scene_classifier.hpp"
#include "perception/scene_monitor.hpp"
#include "rl/learner.hpp"
#include "rl/policy.hpp"
#include "sim/scene.hpp"
#include "task/scripted_pilot.hpp"

namespace comorph::coopt {
namespace {

constexpr int kConfigVector = 4;  // C_n / 10, scene one-hot (stairs, obstacles, target)

// Fixed factors that bring the state's fields to about [-1, 1] (trainer.normalize_state):
// positions over the 6 m area, speeds up to 0.4 m/s, R1 per step about 1.3 at full
// speed, the goal up to 6.5 m away, the mode index 0..2.
float state_scale(int i) {
  namespace o = task::obs;
  if (i == o::kPosition || i == o::kPosition + 1) return 0.2f;
  if (i == o::kPosition + 2) return 5.0f;
  if (i == o::kVelocity || i == o::kVelocity + 1) return 2.5f;
  if (i == o::kPrevReward) return 0.5f;
  if (i == o::kGoal + 2) return 0.2f;
  if (i == o::kMode) return 0.5f;
  return 1.0f;
}

}  // namespace

double motion_gamma(const CooptConfig& c) {
  if (c.trainer.motion_algo == "td3") return c.td3.gamma;
  if (c.trainer.motion_algo == "sac") return c.sac.gamma;
  return 0.99;
}

rl::ObservationSpec motion_spec(const CooptConfig& c) {
  rl::ObservationSpec s;
  if (c.trainer.motion_image) {
    s.image_channels = 1;
    s.image_height = c.env.robot.depth_height;
    s.image_width = c.env.robot.depth_width;
  }
  s.vector_size =
      task::obs::kStateSize + (c.trainer.motion_clearance ? task::MultiTaskEnv::clearance_width(c.env.robot) : 0);
  if (c.trainer.motion_heads_per_chain) {
    s.head_selector = kCandidates;  // the chain lengths
    s.vector_size += s.head_selector;
  }
  return s;
}

rl::ObservationSpec config_spec(const CooptConfig& c) {
  rl::ObservationSpec s;
  s.image_channels = 1;
  s.image_height = c.trainer.decision_camera ? c.env.robot.decision_depth_height : c.env.robot.depth_height;
  s.image_width = c.trainer.decision_camera ? c.env.robot.decision_depth_width : c.env.robot.depth_width;
  s.vector_size = c.trainer.config_vector ? kConfigVector + (c.trainer.config_target_distance ? 1 : 0) : 0;
  return s;
}

void allocate_buffers(const CooptConfig& c, Buffers& b) {
  rl::allocate(motion_spec(c), b.obs);
  rl::allocate(motion_spec(c), b.next);
  rl::allocate(config_spec(c), b.cobs);
  rl::allocate(config_spec(c), b.cnext);
  b.action.continuous.assign(control::kActionSize, 0.0f);
}

task::EpisodeSpec eval_spec(const CooptConfig& c, const task::ScenarioSpec& scenario, std::uint64_t seed, int i) {
  task::EpisodeSpec spec;
  spec.seed = seed;
  const double heights[3] = {c.env.scene.stair_height_a, c.env.scene.stair_height_b, c.env.scene.stair_height_c};
  spec.stair_height = c.trainer.stair_height > 0 ? c.trainer.stair_height : heights[i % 3];
  spec.obstacles = scenario.obstacles;
  spec.variant = scenario.variant;
  return spec;
}

SceneSource::SceneSource(const CooptConfig& c) : params_(c.perception.switch_detector), detector_(params_, 0, 3) {
  if (c.trainer.scene_source == SceneSourceKind::classifier) {
    if (!std::filesystem::exists(std::filesystem::path(c.trainer.classifier_dir) / "classifier.pt"))
      throw std::runtime_error("trainer.classifier_dir: no classifier.pt in '" + c.trainer.classifier_dir +
                               "' (prepare one with `comorph classifier prepare --out " + c.trainer.classifier_dir +
                               "`)");
    classifier_ = std::make_unique<perception::SceneClassifier>(
        perception::SceneClassifier::load(c.trainer.classifier_dir, &c.perception.classifier));
    monitor_ = std::make_unique<perception::SceneMonitor>(*classifier_, params_, 0);
  }
}

SceneSource::~SceneSource() = default;

void SceneSource::reset(const task::MultiTaskEnv& env) {
  step_ = 0;
  if (monitor_) {
    const int first = classifier_->classify(env.depth(), env.depth_height(), env.depth_width());
    monitor_->reset(first);
  } else {
    detector_.reset(label(env));
  }
}

perception::SwitchDecision SceneSource::step(const task::MultiTaskEnv& env) {
  ++step_;
  return monitor_ ? monitor_->step(env.depth()) : detector_.step(label(env));
}

int SceneSource::current() const { return monitor_ ? monitor_->current_scene() : detector_.current_scene(); }

void fill_motion(const float* depth, const float* state, const float* clearance, const TrainerParams& t,
                 rl::Observation& o) {
  if (t.motion_image) std::copy(depth, depth + o.image.size(), o.image.begin());
  for (int i = 0; i < task::obs::kStateSize; ++i) {
    float v = state[i];
    if (t.normalize_state) {
      if (i == task::obs::kPrevReward) v = std::clamp(v, -10.0f, 10.0f);
      v *= state_scale(i);
    }
    o.vector[static_cast<std::size_t>(i)] = v;
  }
  const int selector = t.motion_heads_per_chain ? kCandidates : 0;
  const auto rest = o.vector.begin() + task::obs::kStateSize;  // the clearance row, then the head selector
  if (t.motion_clearance) std::copy(clearance, clearance + (o.vector.end() - rest - selector), rest);
  if (selector > 0) {
    // A one-hot of the chain's length, counted from the state's module mask.
    const int modules = static_cast<int>(
        std::count_if(state + task::obs::kModuleMask, state + task::obs::kModuleMask + kMaxModules,
                      [](float present) { return present > 0.5f; }));
    if (modules < kMinModules)
      throw std::logic_error("fill_motion: a state with " + std::to_string(modules) + " modules");
    const auto block = o.vector.end() - selector;
    std::fill(block, o.vector.end(), 0.0f);
    block[modules - kMinModules] = 1.0f;
  }
}

void fill_config_vector(const TrainerParams& t, const Configuration& current, int scene, double target_distance_m,
                        std::vector<std::uint8_t>& mask, rl::Observation& o) {
  if (t.config_vector) {
    o.vector[0] = static_cast<float>(modules_of(candidate_index(current))) / kMaxModules;
    for (int k = 0; k < 3; ++k) o.vector[1 + k] = scene == k ? 1.0f : 0.0f;
    if (t.config_target_distance) {
      if (!(target_distance_m >= 0))
        throw std::invalid_argument("trainer.config_target_distance: the DQN needs the distance to the target, got " +
                                    std::to_string(target_distance_m) + " m");
      o.vector[kConfigVector] = static_cast<float>(target_distance_m / 10.0);
    }
  }
  candidate_mask(current, mask);
  o.valid_actions = mask;
}

void fill_config(const task::MultiTaskEnv& env, const TrainerParams& t, int scene, bool first,
                 std::vector<std::uint8_t>& mask, rl::Observation& o) {
  if (t.decision_image_first_only && !first)
    std::fill(o.image.begin(), o.image.end(), 0.0f);
  else if (t.decision_camera)
    env.render_decision_depth(o.image.data());
  else
    std::copy(env.depth(), env.depth() + o.image.size(), o.image.begin());
  fill_config_vector(t, env.configuration(), scene, env.target_distance(), mask, o);
}

namespace {


void fill_motion(const task::MultiTaskEnv& env, const TrainerParams& t, rl::Observation& o) {
  fill_motion(env.depth(), env.state(), env.clearance(), t, o);
}

control::MotionMode mode_of(int scene) {
  return scene == sim::kLabelStairs ? control::MotionMode::stair : control::MotionMode::flat;
}

// The segment's R2 as the configuration model is paid it: `r2` (env.task.r2) unless the hooks set another.
float learned_r2(const LearnHooks* hooks, const Segment& segment, const task::MultiTaskEnv& env, double r2) {
  if (hooks->config_r2) r2 = segment.r2(*hooks->config_r2, env.stair_height(), env.stairs_energy());
  return static_cast<float>(r2);
}

void record_first_segment(const CooptConfig& c, const task::MultiTaskEnv& env, const Segment& segment,
                          EpisodeLog& log) {
  log.first_segment_R2 = segment.r2(c.env.task.r2, env.stair_height(), env.stairs_energy());
  log.first_segment_R1 = segment.sum_r1();
  log.first_segment_steps = segment.steps();
}

}  // namespace

void configure_pilot(const TrainerParams& t, task::ScriptedPilot& pilot) {
  if (t.pilot_gait_per_modules)
    pilot.params() = task::searched_stair_gaits();
  else
    pilot.params().gait = {1.0f, 1.0f, -0.5f, 1.0f};  // the gait the physics-table search picks
  pilot.params().flat_steering = t.pilot_flat_steering;
  pilot.params().stair_steering = t.pilot_stair_steering;
}

EpisodeRunner::EpisodeRunner(const CooptConfig& config, std::function<int(int, int)> label_source)
    : config_(config), env_(config.env), scene_(config),
      n_step_(config.trainer.motion_n_step, motion_gamma(config)) {
  scene_.label_source = std::move(label_source);
  allocate_buffers(config, b_);
}

EpisodeLog EpisodeRunner::play(Agent& agent, task::EpisodeSpec spec, bool explore, const LearnHooks* hooks,
                               const StepObserver* observe) {
  const CooptConfig& c = config_;
  task::MultiTaskEnv& env = env_;
  SceneSource& scene = scene_;
  Buffers& b = b_;
  EpisodeLog log;
  const bool hierarchical = agent.hierarchical();
  const TrainerParams& t = c.trainer;
  Configuration configuration = make_chain(c.trainer.fixed_modules);
  double return_r2 = 0;
  Laps* laps = hooks ? hooks->laps : nullptr;
  auto lap = [laps](Phase p) {
    if (laps) laps->lap(p);
  };
  lap(kOther);
  auto choose = [&](rl::Observation& o) -> const Configuration& {
    int a = hooks && hooks->random_config ? hooks->random_config(b.mask) : -1;
    if (a < 0) {
      agent.config->act(o, explore, b.caction);
      a = b.caction.discrete;
    }
    b.caction.discrete = a;
    return candidates()[a];
  };

  // 1. The first configuration decision, on the first depth image (module 1's
  //    camera does not depend on the chain behind it).
  if (hierarchical) {
    spec.configuration = make_chain(kMaxModules);
    env.reset(spec);
    lap(kEnvReset);
    scene.reset(env);
    lap(kClassifier);
    fill_config(env, t, scene.current(), true, b.mask, b.cobs);
    configuration = choose(b.cobs);
    lap(kDqn);
  }
  spec.configuration = configuration;
  env.reset(spec);
  int modules = env.modules();
  lap(kEnvReset);
  scene.reset(env);
  lap(kClassifier);
  task::ScriptedPilot* pilot = hooks ? hooks->pilot : nullptr;
  if (pilot) pilot->plan(env);
  if (observe) (*observe)(env);
  log.configurations.push_back(modules);
  log.modules_total = modules;
  Segment segment;
  segment.begin(false, 0.0);

  // 2. Control steps.
  fill_motion(env, t, b.obs);
  const task::StepOutcome* r = nullptr;
  std::int64_t saturated = 0;
  while (true) {
    // Also when the pilot drives: the same RNG stream.
    agent.motion->act(b.obs, explore && !(hooks && hooks->motion_greedy), b.action);
    if (pilot) {
      control::MotionMode pilot_mode;
      b.action.target.resize(control::kActionSize);  // sized once: no allocation after the first step
      pilot->act(env, b.action.target.data(), pilot_mode);
      if (hooks->pilot_drives && hooks->pilot_noise > 0) {
        std::normal_distribution<float> noise(0.0f, static_cast<float>(hooks->pilot_noise));
        for (int i = 0; i < control::kActionSize; ++i)
          b.action.continuous[i] = std::clamp(b.action.target[i] + noise(*hooks->pilot_rng), -1.0f, 1.0f);
      } else if (hooks->pilot_drives) {
        b.action.continuous = b.action.target;
      }
    } else {
      b.action.target.clear();
    }
    for (float a : b.action.continuous) saturated += std::abs(a) >= 0.99f;
    lap(kActing);
    r = &env.step(b.action.continuous.data(), mode_of(scene.current()));
    lap(kEnvStep);
    if (observe) (*observe)(env);
    segment.add_step(r->reward, r->stairs_climbed_now);
    log.return_R1 += r->reward;
    fill_motion(env, t, b.next);
    lap(kActing);
    const bool done = r->terminated || r->truncated;
    if (hooks) {
      n_step_.add(b.obs, b.action, static_cast<float>(r->reward), b.next, r->terminated, r->truncated, hooks->motion);
      if (hooks->stepped) hooks->stepped(done);
    }
    lap(kHandover);
    std::swap(b.obs, b.next);
    if (done) break;
    const perception::SwitchDecision d = scene.step(env);
    lap(kClassifier);
    if (!d.switched) continue;
    if (log.switches++ == 0) record_first_segment(c, env, segment, log);
    if (!hierarchical) continue;
    // 3. A declared switch ends the segment: one semi-MDP transition, then a
    //    new decision among [2, C_n].
    const double r2 = segment.r2(c.env.task.r2, env.stair_height(), env.stairs_energy());
    return_r2 += r2;
    fill_config(env, t, scene.current(), false, b.mask, b.cnext);
    if (hooks)
      hooks->config(b.cobs, b.caction, learned_r2(hooks, segment, env, r2), b.cnext, false, false, segment.steps());
    std::swap(b.cobs, b.cnext);
    const Configuration& next = choose(b.cobs);
    lap(kDqn);
    if (next != env.configuration()) {
      env.reconfigure(next);
      modules = env.modules();
      lap(kEnvReset);
      fill_motion(env, t, b.obs);
    }
    if (log.configurations.back() != modules) log.configurations.push_back(modules);
    segment.begin(env.stairs_climbed(), env.stairs_energy());
    lap(kActing);
  }
  // 4. The last segment.
  if (log.switches == 0) record_first_segment(c, env, segment, log);
  if (hierarchical) {
    const double r2 = segment.r2(c.env.task.r2, env.stair_height(), env.stairs_energy());
    return_r2 += r2;
    fill_config(env, t, scene.current(), false, b.mask, b.cnext);
    if (hooks)
      hooks->config(b.cobs, b.caction, learned_r2(hooks, segment, env, r2), b.cnext, r->terminated, r->truncated,
                    segment.steps());
    lap(kDqn);
  }

  const task::EpisodeMetrics m = env.metrics();
  log.seed = spec.seed;
  log.scenario = name_of(c.trainer.scenario);
  log.stair_height_m = env.stair_height();
  log.obstacles = static_cast<int>(env.world().layout().obstacles.size());
  log.success = r->reason == task::Termination::success;
  log.termination = task::termination_name(r->reason);
  log.time_s = m.time_s;
  log.energy_J = m.energy_J;
  log.distance_fraction = m.D;
  log.F = m.F;
  log.return_R2 = return_r2;
  log.steps = m.steps;
  log.stairs_energy_J = env.stairs_energy();
  log.stairs_climbed = env.stairs_climbed();
  log.action_saturation =
      m.steps > 0 ? static_cast<double>(saturated) / (static_cast<double>(m.steps) * control::kActionSize) : 0.0;
  lap(kOther);
  return log;
}

}  // namespace comorph::coopt
