// The hierarchical trainer and the evaluator (see trainer.hpp for the loop).
#include "coopt/trainer.hpp"

#include <torch/torch.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include "common/checksum.hpp"
#include "common/file_io.hpp"
#include "coopt/segment.hpp"
#include "perception/scene_classifier.hpp"
#include "perception/scene_monitor.hpp"
#include "perception/switch_detector.hpp"
#include "rl/dqn.hpp"
#include "rl/replay_segments.hpp"
#include "rl/sac.hpp"
#include "rl/td3.hpp"
#include "sim/scene.hpp"
#include "task/multitask_env.hpp"
#include "task/scripted_pilot.hpp"

namespace comorph::coopt {
namespace fs = std::filesystem;
namespace {

constexpr int kConfigVector = 4;  // C_n / 10, scene one-hot (stairs, obstacles, target)
using Clock = std::chrono::steady_clock;

// Where the acting thread's time goes (TrainerTiming): each lap() gives the
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

// ---------------------------------------------------------------------------
// Learners

rl::ObservationSpec motion_spec(const CooptConfig& c) {
  rl::ObservationSpec s;
  if (c.trainer.motion_image) {
    s.image_channels = 1;
    s.image_height = c.env.robot.depth_height;
    s.image_width = c.env.robot.depth_width;
  }
  s.vector_size =
      task::obs::kStateSize + (c.trainer.motion_clearance ? task::MultiTaskEnv::clearance_width(c.env.robot) : 0);
  return s;
}

rl::ObservationSpec config_spec(const CooptConfig& c) {
  rl::ObservationSpec s;
  s.image_channels = 1;
  s.image_height = c.trainer.decision_camera ? c.env.robot.decision_depth_height : c.env.robot.depth_height;
  s.image_width = c.trainer.decision_camera ? c.env.robot.decision_depth_width : c.env.robot.depth_width;
  s.vector_size = c.trainer.config_vector ? kConfigVector : 0;
  return s;
}

// The motion learner; `replica` = the acting copy (one-slot replay).
std::unique_ptr<rl::Learner> make_motion(const CooptConfig& c, std::uint64_t seed, bool replica) {
  const rl::ObservationSpec spec = motion_spec(c);
  if (c.trainer.motion_algo == "sac") {
    rl::SacConfig cfg = c.sac;
    cfg.random_action_episodes = c.trainer.warmup_episodes;
    if (replica) cfg.buffer_size = 1;
    return std::make_unique<rl::Sac>(spec, control::kActionSize, cfg, seed);
  }
  rl::Td3Config cfg = c.td3;
  cfg.random_action_episodes = c.trainer.warmup_episodes;
  if (replica) cfg.buffer_size = 1;
  return std::make_unique<rl::Td3>(spec, control::kActionSize, cfg, seed);
}

rl::ActorCritic& networks_of(rl::Learner& l) {
  if (auto* t = dynamic_cast<rl::Td3*>(&l)) return t->networks();
  if (auto* s = dynamic_cast<rl::Sac*>(&l)) return s->networks();
  throw std::logic_error("motion learner is neither TD3 nor SAC");
}

std::unique_ptr<rl::Dqn> make_config_model(const CooptConfig& c, std::uint64_t seed) {
  if (c.trainer.mode != "hierarchical") return nullptr;
  return std::make_unique<rl::Dqn>(config_spec(c), kCandidates, c.dqn, seed);
}

// ---------------------------------------------------------------------------
// Scene source: the switch detector on ground-truth labels or on the classifier.

class SceneSource {
 public:
  explicit SceneSource(const CooptConfig& c) : params_(c.perception.switch_detector), detector_(params_, 0, 3) {
    if (c.trainer.scene_source == "classifier") {
      classifier_ = std::make_unique<perception::SceneClassifier>(
          perception::SceneClassifier::load(c.trainer.classifier_dir, &c.perception.classifier));
      monitor_ = std::make_unique<perception::SceneMonitor>(*classifier_, params_, 0);
    }
  }
  std::function<int(int, int)> label_source;  // optional relabelling of the ground truth

  void reset(const task::MultiTaskEnv& env) {
    step_ = 0;
    if (monitor_) {
      const int first = classifier_->classify(env.depth(), env.depth_height(), env.depth_width());
      monitor_->reset(first);
    } else {
      detector_.reset(label(env));
    }
  }
  perception::SwitchDecision step(const task::MultiTaskEnv& env) {
    ++step_;
    return monitor_ ? monitor_->step(env.depth()) : detector_.step(label(env));
  }
  int current() const { return monitor_ ? monitor_->current_scene() : detector_.current_scene(); }

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

// ---------------------------------------------------------------------------
// What acts in an episode: the motion actor and the configuration model.

struct Agent {
  std::unique_ptr<rl::Learner> motion;   // acting copy of the motion model
  std::unique_ptr<rl::Dqn> config;       // nullptr in fixed mode
};

// Training hooks of one episode (absent for evaluation).
struct LearnHooks {
  std::function<void(const rl::Observation&, const rl::Action&, float, const rl::Observation&, bool, bool)> motion;
  std::function<void(const rl::Observation&, const rl::Action&, float, const rl::Observation&, bool, bool, int)>
      config;
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

// Reusable buffers of an episode runner (no allocation in the step loop).
struct Buffers {
  rl::Observation obs, next, cobs, cnext;
  rl::Action action, caction;
  std::vector<std::uint8_t> mask;
};

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

// The motion model's input from the env's observation (depth(), state(),
// clearance()): the image if asked, the state (scaled if asked), then the
// clearance row if asked.
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
  if (t.motion_clearance)
    std::copy(clearance, clearance + (o.vector.size() - task::obs::kStateSize), o.vector.begin() + task::obs::kStateSize);
}

void fill_motion(const task::MultiTaskEnv& env, const TrainerParams& t, rl::Observation& o) {
  fill_motion(env.depth(), env.state(), env.clearance(), t, o);
}

// The configuration model's vector [C_n / 10, scene one-hot] and mask (the current
// configuration and those it can shed modules to); the image is already in o.image.
void fill_config_vector(const TrainerParams& t, const Configuration& current, int scene, Buffers& b,
                        rl::Observation& o) {
  const bool vector = t.config_vector;
  if (vector) {
    o.vector[0] = static_cast<float>(modules_of(candidate_index(current))) / kMaxModules;
    for (int k = 0; k < 3; ++k) o.vector[1 + k] = scene == k ? 1.0f : 0.0f;
  }
  candidate_mask(current, b.mask);
  o.valid_actions = b.mask;
}

void fill_config(const task::MultiTaskEnv& env, const TrainerParams& t, int scene, Buffers& b, rl::Observation& o) {
  if (t.decision_camera)
    env.render_decision_depth(o.image.data());
  else
    std::copy(env.depth(), env.depth() + o.image.size(), o.image.begin());
  fill_config_vector(t, env.configuration(), scene, b, o);
}

control::MotionMode mode_of(int scene) {
  return scene == sim::kLabelStairs ? control::MotionMode::stair : control::MotionMode::flat;
}

void record_first_segment(const CooptConfig& c, const task::MultiTaskEnv& env, const Segment& segment,
                          EpisodeLog& log) {
  log.first_segment_R2 = segment.r2(c.env.task.r2, env.stair_height(), env.stairs_energy());
  log.first_segment_R1 = segment.sum_r1();
  log.first_segment_steps = segment.steps();
}

// One episode; learn == hooks present. The env is reset here. `observe` (may
// be null) sees the env after the reset that starts control and after every step.
EpisodeLog play(const CooptConfig& c, Agent& agent, task::MultiTaskEnv& env, SceneSource& scene,
                task::EpisodeSpec spec, bool explore, const LearnHooks* hooks, Buffers& b,
                const StepObserver* observe = nullptr) {
  EpisodeLog log;
  const bool hierarchical = agent.config != nullptr;
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
    fill_config(env, t, scene.current(), b, b.cobs);
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
  const task::StepResult* r = nullptr;
  std::int64_t saturated = 0;
  while (true) {
    // Also when the pilot drives: the same RNG stream.
    agent.motion->act(b.obs, explore && !(hooks && hooks->motion_greedy), b.action);
    if (pilot) {
      control::MotionMode pilot_mode;
      b.action.target.resize(control::kActionSize);  // sized once: no allocation after the first step
      pilot->act(env, b.action.target.data(), pilot_mode);
      if (hooks->pilot_drives) {
        std::normal_distribution<float> noise(0.0f, static_cast<float>(hooks->pilot_noise));
        for (int i = 0; i < control::kActionSize; ++i)
          b.action.continuous[i] = std::clamp(b.action.target[i] + noise(*hooks->pilot_rng), -1.0f, 1.0f);
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
    if (hooks) hooks->motion(b.obs, b.action, static_cast<float>(r->reward), b.next, r->terminated, r->truncated);
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
    fill_config(env, t, scene.current(), b, b.cnext);
    if (hooks) hooks->config(b.cobs, b.caction, static_cast<float>(r2), b.cnext, false, false, segment.steps());
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
    fill_config(env, t, scene.current(), b, b.cnext);
    if (hooks)
      hooks->config(b.cobs, b.caction, static_cast<float>(r2), b.cnext, r->terminated, r->truncated, segment.steps());
    lap(kDqn);
  }

  const task::Metrics m = env.metrics();
  log.seed = spec.seed;
  log.scenario = c.trainer.scenario;
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

void allocate_buffers(const CooptConfig& c, Buffers& b) {
  rl::allocate(motion_spec(c), b.obs);
  rl::allocate(motion_spec(c), b.next);
  rl::allocate(config_spec(c), b.cobs);
  rl::allocate(config_spec(c), b.cnext);
  b.action.continuous.assign(control::kActionSize, 0.0f);
}

// The scene spec of an evaluation episode (heights cycle 0.04, 0.06, 0.08).
task::EpisodeSpec eval_spec(const CooptConfig& c, const std::string& scenario, std::uint64_t seed, int i) {
  task::EpisodeSpec spec;
  spec.seed = seed;
  const double heights[3] = {c.env.scene.stair_height_a, c.env.scene.stair_height_b, c.env.scene.stair_height_c};
  spec.stair_height = c.trainer.stair_height > 0 ? c.trainer.stair_height : heights[i % 3];
  bool mixed = false;
  scenario_settings(scenario, spec.obstacles, mixed);
  spec.variant = mixed ? sim::Variant::mixed : sim::Variant::standard;
  return spec;
}

// ---------------------------------------------------------------------------
// The learner thread: runs one job at a time (store + updates of an interval).

class LearnerWorker {
 public:
  explicit LearnerWorker(bool threaded) : threaded_(threaded) {
    if (threaded_) thread_ = std::thread([this] { loop(); });
  }
  ~LearnerWorker() {
    if (!threaded_) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      quit_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  void submit(std::function<void()> job) {
    if (!threaded_) {
      job();
      return;
    }
    wait();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      job_ = std::move(job);
      pending_ = true;
    }
    cv_.notify_all();
  }
  void wait() {
    if (!threaded_) return;
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [this] { return !pending_; });
    if (error_) {
      auto e = error_;
      error_ = nullptr;
      std::rethrow_exception(e);
    }
  }

 private:
  void loop() {
    while (true) {
      std::function<void()> job;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        cv_.wait(lock, [this] { return pending_ || quit_; });
        if (quit_ && !pending_) return;
        job = std::move(job_);
      }
      try {
        job();
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex_);
        error_ = std::current_exception();
      }
      {
        std::lock_guard<std::mutex> lock(mutex_);
        pending_ = false;
      }
      cv_.notify_all();
    }
  }
  bool threaded_;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::function<void()> job_;
  bool pending_ = false, quit_ = false;
  std::exception_ptr error_;
};

struct Transition {
  rl::Observation obs, next;
  rl::Action action;
  float reward = 0;
  bool terminated = false, truncated = false;
};

std::string checkpoint_dir(const std::string& run) { return (fs::path(run) / "checkpoint").string(); }

void write_text_file(const std::string& path, const std::string& text) { write_file_atomic(path, text); }

// Loads one checkpoint file into a learner. LibTorch's errors (a C++ backtrace
// of 20 lines) become one line naming the file.
template <class Model>
void load_checkpoint_file(Model& model, const std::string& path) {
  try {
    model.load(path);
  } catch (const c10::Error& e) {
    const std::string what = e.what_without_backtrace();
    throw std::runtime_error(path + ": cannot load: " + quote_value(what.substr(0, what.find('\n')), 200));
  }
}

// A learner's replay from its checkpoint's segments (rl/replay_segments.hpp;
// an older checkpoint's learner file held it, and then there is no index).
// Every transition the learner counts must be back: a missing index would
// otherwise resume with an empty buffer.
rl::ReplaySegments load_replay(rl::Learner& learner, const std::string& name, const std::string& dir) {
  rl::ReplaySegments segments = rl::read_replay_segments(learner.replay(), name, dir);
  const rl::ReplayBuffer& replay = learner.replay();
  const std::int64_t expected = std::min(learner.counters().transitions, replay.capacity());
  if (replay.size() != expected)
    throw std::runtime_error((fs::path(dir) / rl::replay_index_name(name)).string() + ": the replay holds " +
                             std::to_string(replay.size()) + " transitions, the learner stored " +
                             std::to_string(learner.counters().transitions) + " (capacity " +
                             std::to_string(replay.capacity()) + ")");
  return segments;
}

std::string first_difference(const std::string& a, const std::string& b) {
  std::istringstream sa(a), sb(b);
  std::string la, lb;
  int line = 0;
  while (true) {
    const bool ga = static_cast<bool>(std::getline(sa, la));
    const bool gb = static_cast<bool>(std::getline(sb, lb));
    ++line;
    if (!ga && !gb) return "";
    if (!ga || !gb || la != lb)
      return "line " + std::to_string(line) + ": checkpoint has '" + quote_value(gb ? lb : "<end>") +
             "', config has '" + quote_value(ga ? la : "<end>") + "'";
  }
}

}  // namespace

// ---------------------------------------------------------------------------

CheckpointInfo read_checkpoint_info(const std::string& run_dir) {
  // checkpoint/ is the newest; checkpoint.old/ the one before it (and the only
  // one after a crash between the two renames of save_checkpoint). The first
  // whose files all match their checksums is used; a damaged one is named.
  std::string dir, problems;
  for (const std::string& candidate : {checkpoint_dir(run_dir), checkpoint_dir(run_dir) + ".old"}) {
    if (!fs::exists(candidate)) continue;
    std::string problem;
    if (!fs::exists(fs::path(candidate) / "trainer.yaml")) {
      problem = candidate + ": incomplete (no trainer.yaml)";
    } else if (!fs::exists(fs::path(candidate) / kChecksumFile)) {
      std::fprintf(stderr, "comorph: warning: %s has no %s (written before checkpoints had checksums): not verified\n",
                   candidate.c_str(), kChecksumFile);
    } else {
      problem = verify_checksums(candidate);
    }
    if (problem.empty()) {
      dir = candidate;
      break;
    }
    problems += (problems.empty() ? "" : "; ") + problem;
  }
  if (dir.empty())
    throw std::runtime_error(problems.empty() ? run_dir + ": no checkpoint (expected " + checkpoint_dir(run_dir) + ")"
                                              : problems + "; no usable checkpoint in " + run_dir);
  if (!problems.empty()) std::fprintf(stderr, "comorph: %s; using the previous checkpoint %s\n", problems.c_str(), dir.c_str());
  const std::string path = (fs::path(dir) / "trainer.yaml").string();
  CheckpointInfo info;
  try {
    const YAML::Node n = load_yaml_file(path);
    info.episodes = n["episodes"].as<int>();
    info.evaluations = n["evaluations"].as<int>();
    info.env_steps = n["env_steps"].as<std::int64_t>();
    info.wall_s = n["wall_s"].as<double>();
    info.config_text = n["config"].as<std::string>();
    if (n["env_files"]) info.env_text = n["env_files"].as<std::string>();
    info.has_env_text = static_cast<bool>(n["env_files"]);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(path + ": unreadable checkpoint: " + e.msg);
  }
  info.directory = dir;
  return info;
}

void check_checkpoint_counts(const CheckpointInfo& info, const CooptConfig& config) {
  const int total = config.trainer.total_episodes();
  if (info.episodes < 0 || info.episodes > total)
    throw std::runtime_error(info.directory + ": the checkpoint counts " + std::to_string(info.episodes) +
                             " episodes, the config has " + std::to_string(total) +
                             " (warm-up + training + DQN refit); refusing to resume");
  if (info.evaluations < 0 || info.evaluations > info.episodes)
    throw std::runtime_error(info.directory + ": the checkpoint counts " + std::to_string(info.evaluations) +
                             " evaluations after " + std::to_string(info.episodes) +
                             " episodes; refusing to resume");
  if (info.env_steps < 0 || info.wall_s < 0)
    throw std::runtime_error(info.directory + ": the checkpoint counts " + std::to_string(info.env_steps) +
                             " control steps and " + std::to_string(info.wall_s) + " s; refusing to resume");
}

void check_same_run(const CheckpointInfo& info, const CooptConfig& config, const std::string& run_dir) {
  if (info.config_text != config.text)
    throw std::runtime_error(run_dir + ": the checkpoint was written by another configuration (" +
                             first_difference(config.text, info.config_text) + ")");
  if (!info.has_env_text)
    std::fprintf(stderr, "comorph: warning: %s predates simulator-config checks: configs/sim not compared\n",
                 info.directory.c_str());
  else if (info.env_text != config.env_text)
    throw std::runtime_error(run_dir + ": the simulator config (" + config.env_dir +
                             ") changed since the checkpoint was written (" +
                             first_difference(config.env_text, info.env_text) + ")");
}

void truncate_csv_rows(const std::string& path, int rows) {
  if (!fs::exists(path)) return;
  std::ifstream in(path);
  std::string text, line;
  int kept = -1;  // the header is row -1
  while (kept < rows && std::getline(in, line)) {
    text += line + "\n";
    ++kept;
  }
  in.close();
  write_text_file(path, text);
}

struct Trainer::Impl {
  CooptConfig config;
  std::string run_dir;
  TrainerCallbacks callbacks;

  std::unique_ptr<rl::Learner> learner;  // full motion learner (learner thread)
  Agent agent;                           // acting copy + configuration model (acting thread)
  task::MultiTaskEnv env;
  SceneSource scene;
  Buffers buffers;
  std::mt19937_64 rng;                   // warm-up configuration choices, noise on the pilot's actions
  task::ScriptedPilot pilot;             // demonstrations and targets (warmup_policy: scripted, pilot_labels)

  // Hand-over buffers: `filling` is written by the acting thread while the
  // learner consumes the other one.
  std::vector<Transition> pending[2];
  int filling = 0, filled = 0;
  // trainer.config_target: return: the episode's decisions, stored at its end.
  // Their observations and actions, and their R2 (turned into returns).
  std::vector<Transition> episode_decisions;
  std::vector<float> episode_decision_returns;
  std::unique_ptr<LearnerWorker> worker;

  int episode = 0, evaluations = 0;
  std::int64_t steps = 0;
  double wall_before = 0;  // wall time of earlier sessions (resume), s
  Clock::time_point started = Clock::now();
  std::vector<double> recent_success;  // last 20 training episodes

  // TrainerTiming: the acting thread's laps, run()'s wall time and checkpoints,
  // and the learner's job time (written by the job, read after worker->wait()).
  Laps laps;
  Clock::duration run_time{}, learner_busy{};
  int run_checkpoints = 0;
  // measure_side_rates: when set, the acting side records its transitions
  // here (preallocated) instead of handing them to the learner.
  std::vector<Transition>* record = nullptr;
  std::size_t recorded = 0;
  // The replay segments of the last checkpoint written or loaded: the next
  // checkpoint links those and writes only what was added since.
  rl::ReplaySegments motion_segments, config_segments;

  Impl(const CooptConfig& c, const std::string& dir, TrainerCallbacks cb)
      : config(c), run_dir(dir), callbacks(std::move(cb)), env(c.env), scene(c), rng(c.trainer.seed * 7919ULL + 17) {
    rl::set_torch_threads(c.trainer.torch_threads, 1);
    const std::uint64_t seed = static_cast<std::uint64_t>(c.trainer.seed);
    learner = make_motion(c, seed, false);
    agent.motion = make_motion(c, seed + 1, true);
    rl::copy_parameters(*networks_of(*agent.motion), *networks_of(*learner));
    agent.config = make_config_model(c, seed + 2);
    allocate_buffers(c, buffers);
    for (auto& p : pending) {
      p.resize(c.trainer.sync_interval);
      for (auto& t : p) {
        rl::allocate(motion_spec(c), t.obs);
        rl::allocate(motion_spec(c), t.next);
        t.action.continuous.assign(control::kActionSize, 0.0f);
      }
    }
    worker = std::make_unique<LearnerWorker>(c.trainer.learner_thread);
    scene.label_source = callbacks.label_source;
    if (c.trainer.pilot_gait_per_modules)
      pilot.params() = task::searched_stair_gaits();
    else
      pilot.params().gait = {1.0f, 1.0f, -0.5f, 1.0f};  // the gait the physics-table search picks
  }

  double wall() const { return wall_before + std::chrono::duration<double>(Clock::now() - started).count(); }

  // Hands the filled transitions to the learner (after its previous job) and
  // refreshes the acting copy's weights from the learner.
  void hand_over() {
    laps.lap(kHandover);
    worker->wait();
    laps.lap(kWaiting);
    rl::copy_parameters(*networks_of(*agent.motion), *networks_of(*learner));
    laps.lap(kHandover);
    if (filled == 0) return;
    std::vector<Transition>* batch = &pending[filling];
    const int n = filled;
    filling = 1 - filling;
    filled = 0;
    rl::Learner* l = learner.get();
    Clock::duration* busy = &learner_busy;
    worker->submit([l, batch, n, busy] {
      const Clock::time_point start = Clock::now();
      for (int i = 0; i < n; ++i) {
        const Transition& t = (*batch)[i];
        l->store(t.obs, t.action, t.reward, t.next, t.terminated, t.truncated);
        for (int u = l->updates_due(); u > 0; --u) l->update();
      }
      *busy += Clock::now() - start;
    });
    laps.lap(config.trainer.learner_thread ? kHandover : kMotionUpdates);  // inline: the job ran in submit()
  }

  // Episode end: everything handed over and learnt, acting copy up to date.
  void full_sync() {
    hand_over();
    worker->wait();
    laps.lap(kWaiting);
    rl::copy_parameters(*networks_of(*agent.motion), *networks_of(*learner));
    laps.lap(kHandover);
  }

  // trainer.config_target: return. Each decision of the ended episode is
  // stored with the R2 of its own and every later segment (each later one
  // discounted once more by dqn.gamma) as a terminal transition.
  void learn_episode_returns() {
    to_decision_returns(episode_decision_returns, config.dqn.gamma);
    for (std::size_t i = 0; i < episode_decisions.size(); ++i) {
      const Transition& d = episode_decisions[i];
      // Terminal: no bootstrap, so the segment's length (the discount's k) plays no part.
      agent.config->store(d.obs, d.action, episode_decision_returns[i], d.next, /*terminated=*/true, false);
      for (int u = agent.config->updates_due(); u > 0; --u) agent.config->update();
    }
    episode_decisions.clear();
    episode_decision_returns.clear();
  }

  EpisodeLog train_episode() {
    const TrainerParams& t = config.trainer;
    const bool warmup = episode < t.warmup_episodes;
    // The DQN refit (trainer.config_refit_episodes): a fresh DQN on the frozen,
    // greedy motion model; no pilot, nothing stored for the motion learner.
    const bool refit = episode >= t.warmup_episodes + t.episodes;
    if (refit && episode == t.warmup_episodes + t.episodes) {
      agent.config = make_config_model(config, static_cast<std::uint64_t>(t.seed) + 3);
      config_segments = {};  // its replay starts empty: no segment of the old one to link
    }
    LearnHooks hooks;
    hooks.laps = &laps;
    if (refit)
      hooks.motion = [this](const rl::Observation&, const rl::Action&, float, const rl::Observation&, bool, bool) {
        ++steps;
      };
    else
      hooks.motion = [this](const rl::Observation& o, const rl::Action& a, float r, const rl::Observation& n,
                            bool term, bool trunc) {
        agent.motion->store(o, a, r, n, term, trunc);  // keeps the acting copy's exploration counters
        Transition& tr = record ? (*record)[recorded++] : pending[filling][filled++];
        tr.obs.image = o.image;  // same sizes: copies, no allocation
        tr.obs.vector = o.vector;
        tr.next.image = n.image;
        tr.next.vector = n.vector;
        tr.action.continuous = a.continuous;
        tr.action.target = a.target;
        tr.reward = r;
        tr.terminated = term;
        tr.truncated = trunc;
        ++steps;
        if (!record && filled == config.trainer.sync_interval) hand_over();
      };
    const bool scripted = !refit && t.warmup_policy == "scripted" &&
                          (warmup || (t.scripted_interval > 0 && episode % t.scripted_interval == 0));
    const bool greedy_motion = refit || (!warmup && !scripted && t.greedy_motion_interval > 0 &&
                                         episode % t.greedy_motion_interval == 1 % t.greedy_motion_interval);
    const bool config_learns = refit || t.config_learns_from == "all" ||
                               (t.config_learns_from == "model" && !scripted) ||
                               (t.config_learns_from == "greedy" && greedy_motion);
    hooks.motion_greedy = greedy_motion;
    hooks.config = [this, config_learns](const rl::Observation& o, const rl::Action& a, float r2,
                                         const rl::Observation& n, bool term, bool trunc, int k) {
      if (!config_learns) return;
      if (config.trainer.config_target == "return") {
        Transition& d = episode_decisions.emplace_back();  // 2 or 3 an episode
        d.obs = o;
        d.next = n;
        d.action = a;
        episode_decision_returns.push_back(r2);
        if (term || trunc) learn_episode_returns();
      } else {
        agent.config->store(o, a, r2, n, term, trunc, k);
        for (int u = agent.config->updates_due(); u > 0; --u) agent.config->update();
      }
      if (callbacks.on_decision) {
        DecisionLog d;
        d.episode = episode;
        d.step = env.step_count();
        d.modules = modules_of(a.discrete);
        d.r2 = r2;
        d.k = k;
        for (int c = 0; c < kCandidates; ++c)
          if (n.valid_actions[c]) d.next_max_modules = modules_of(c);
        d.terminated = term;
        d.truncated = trunc;
        callbacks.on_decision(d);
      }
    };
    if (warmup || (scripted && t.pilot_random_configs))
      hooks.random_config = [this](const std::vector<std::uint8_t>& mask) {
        int valid = 0;
        for (auto m : mask) valid += m;
        int k = std::uniform_int_distribution<int>(0, valid - 1)(rng);
        for (int a = 0; a < static_cast<int>(mask.size()); ++a)
          if (mask[a] && k-- == 0) return a;
        return -1;
      };
    if (scripted || (t.pilot_labels && !refit)) {
      hooks.pilot = &pilot;
      hooks.pilot_drives = scripted;
      hooks.pilot_noise = t.warmup_noise;
      hooks.pilot_rng = &rng;
    }
    task::EpisodeSpec spec;
    spec.seed = static_cast<std::uint64_t>(t.seed) * 1000003ULL + static_cast<std::uint64_t>(episode);
    spec.stair_height = t.stair_height;
    bool mixed = false;
    scenario_settings(t.scenario, spec.obstacles, mixed);
    spec.variant = mixed ? sim::Variant::mixed : sim::Variant::standard;
    EpisodeLog log = play(config, agent, env, scene, spec, true, &hooks, buffers);
    if (!record) full_sync();
    log.episode = episode;
    log.warmup = warmup;
    return log;
  }

  EvaluationLog periodic_evaluation() {
    EvaluationLog e;
    e.train_episode = episode;
    e.env_steps = steps;
    e.wall_s = wall();
    for (int i = 0; i < config.trainer.eval_episodes; ++i) {
      const auto spec = eval_spec(config, config.trainer.scenario,
                                  static_cast<std::uint64_t>(config.trainer.eval_seed) + i, i);
      EpisodeLog log = play(config, agent, env, scene, spec, false, nullptr, buffers);
      log.episode = i;
      e.episodes.push_back(std::move(log));
    }
    return e;
  }

  void progress(const EpisodeLog& log) {
    recent_success.push_back(log.success ? 1.0 : 0.0);
    if (recent_success.size() > 20) recent_success.erase(recent_success.begin());
    const TrainerParams& t = config.trainer;
    const int total = t.total_episodes();
    if (episode % t.progress_interval != 0 && episode != total) return;
    double rate = 0;
    for (double s : recent_success) rate += s;
    rate /= static_cast<double>(recent_success.size());
    const double w = wall();
    const double eta_s = episode > 0 ? w / episode * (total - episode) : 0;
    const std::string configs = task::configuration_sequence(log.configurations);
    std::fprintf(stderr,
                 "episode %d/%d%s | %d steps, return %.1f, %s | total %lld steps, %.0f steps/s | success %.0f %% "
                 "(last %zu) | config %s (stairs %.2f m) | wall %.0f s, ETA %.0f s\n",
                 episode, total, log.warmup ? " (warm-up)" : "", log.steps, log.return_R1, log.termination.c_str(),
                 static_cast<long long>(steps), w > 0 ? steps / w : 0.0, 100.0 * rate, recent_success.size(),
                 configs.c_str(), log.stair_height_m, w, eta_s);
  }

  void save_checkpoint() {
    full_sync();
    const std::string dir = checkpoint_dir(run_dir);
    const std::string tmp = dir + ".tmp", old = dir + ".old";
    fs::remove_all(tmp);
    fs::create_directories(tmp);
    rl::ReplaySegments motion_next, config_next;
    try {
      write_checkpoint_files(tmp, motion_next, config_next);
    } catch (...) {
      // A full disk: the last good checkpoint stays; free what the partial one took.
      std::error_code ignored;
      fs::remove_all(tmp, ignored);
      try {
        throw;
      } catch (const c10::Error& e) {  // any other LibTorch failure: one line, no backtrace
        const std::string what = e.what_without_backtrace();
        throw std::runtime_error("cannot write the checkpoint " + tmp + ": " + what.substr(0, what.find('\n')));
      }
    }
    // Swap directories: a crash at any point leaves either `checkpoint` or
    // `checkpoint.old` complete (read_checkpoint_info falls back to .old).
    // checkpoint.old stays as the fallback when `checkpoint` is found damaged.
    // The replay segments live in each directory that needs them (hard
    // links), so removing checkpoint.old takes nothing from the others.
    fs::remove_all(old);
    if (fs::exists(dir)) fs::rename(dir, old);
    fs::rename(tmp, dir);
    motion_segments = motion_next;
    motion_segments.directory = dir;
    config_segments = config_next;
    config_segments.directory = dir;
  }

  // The files of a checkpoint into `tmp`, the checksums last. The replay
  // buffers go apart from their learners, as segments: only the transitions
  // added since the last checkpoint are written (rl/replay_segments.hpp).
  void write_checkpoint_files(const std::string& tmp, rl::ReplaySegments& motion_next,
                              rl::ReplaySegments& config_next) {
    std::vector<std::string> files{"motion.pt", "motion_actor.pt", "trainer.yaml"};
    std::map<std::string, std::string> sums;  // of linked segments, known without reading them
    learner->save_without_replay((fs::path(tmp) / "motion.pt").string());
    motion_next = rl::write_replay_segments(learner->replay(), "motion", tmp, motion_segments, files, sums);
    agent.motion->save((fs::path(tmp) / "motion_actor.pt").string());  // the acting copy: a one-slot replay
    if (agent.config) {
      agent.config->save_without_replay((fs::path(tmp) / "config_model.pt").string());
      files.push_back("config_model.pt");
      config_next =
          rl::write_replay_segments(agent.config->replay(), "config_model", tmp, config_segments, files, sums);
    }
    YAML::Emitter e;
    e << YAML::BeginMap;
    e << YAML::Key << "episodes" << YAML::Value << episode;
    e << YAML::Key << "evaluations" << YAML::Value << evaluations;
    e << YAML::Key << "env_steps" << YAML::Value << steps;
    e << YAML::Key << "wall_s" << YAML::Value << wall();
    e << YAML::Key << "rng" << YAML::Value << rl::rng_state(rng);
    // env_files ends with a newline, which a literal block keeps; config has
    // none, which only the last value of the document keeps.
    e << YAML::Key << "env_files" << YAML::Value << YAML::Literal << config.env_text;
    e << YAML::Key << "config" << YAML::Value << YAML::Literal << config.text;
    e << YAML::EndMap;
    write_text_file((fs::path(tmp) / "trainer.yaml").string(), e.c_str());
    write_checksums(tmp, files, sums);
  }

  void load_checkpoint() {
    const CheckpointInfo info = read_checkpoint_info(run_dir);
    try {
      check_same_run(info, config, run_dir);
      check_checkpoint_counts(info, config);
    } catch (const std::exception& e) {
      throw std::runtime_error(std::string(e.what()) + "; refusing to resume");
    }
    load_checkpoint_file(*learner, (fs::path(info.directory) / "motion.pt").string());
    motion_segments = load_replay(*learner, "motion", info.directory);
    load_checkpoint_file(*agent.motion, (fs::path(info.directory) / "motion_actor.pt").string());
    if (agent.config) {
      load_checkpoint_file(*agent.config, (fs::path(info.directory) / "config_model.pt").string());
      config_segments = load_replay(*agent.config, "config_model", info.directory);
    }
    const YAML::Node n = load_yaml_file((fs::path(info.directory) / "trainer.yaml").string());
    rl::set_rng_state(rng, n["rng"].as<std::string>());
    episode = info.episodes;
    evaluations = info.evaluations;
    steps = info.env_steps;
    wall_before = info.wall_s;
    started = Clock::now();
    truncate_csv_rows((fs::path(run_dir) / "episodes.csv").string(), episode);
    truncate_csv_rows((fs::path(run_dir) / "evaluations.csv").string(), evaluations);
  }
};

Trainer::Trainer(const CooptConfig& config, const std::string& run_dir, TrainerCallbacks callbacks)
    : impl_(std::make_unique<Impl>(config, run_dir, std::move(callbacks))) {}
Trainer::~Trainer() = default;

void Trainer::resume() { impl_->load_checkpoint(); }
void Trainer::checkpoint() { impl_->save_checkpoint(); }
int Trainer::episodes_done() const { return impl_->episode; }
int Trainer::evaluations_done() const { return impl_->evaluations; }
std::int64_t Trainer::env_steps() const { return impl_->steps; }
double Trainer::wall_s() const { return impl_->wall(); }

TrainerTiming Trainer::timing() const {
  const Impl& m = *impl_;
  auto s = [](Clock::duration d) { return std::chrono::duration<double>(d).count(); };
  TrainerTiming t;
  t.wall_s = s(m.run_time);
  using Field = double TrainerTiming::*;
  const std::pair<Phase, Field> fields[] = {
      {kEnvStep, &TrainerTiming::env_step_s},       {kEnvReset, &TrainerTiming::env_reset_s},
      {kActing, &TrainerTiming::acting_s},          {kHandover, &TrainerTiming::handover_s},
      {kWaiting, &TrainerTiming::waiting_s},        {kMotionUpdates, &TrainerTiming::motion_updates_s},
      {kDqn, &TrainerTiming::dqn_s},                {kClassifier, &TrainerTiming::classifier_s},
      {kEvaluation, &TrainerTiming::evaluation_s},  {kCheckpoint, &TrainerTiming::checkpoint_s},
      {kLogging, &TrainerTiming::logging_s},        {kOther, &TrainerTiming::other_s}};
  for (const auto& [phase, field] : fields) t.*field = s(m.laps.spent[phase]);
  t.learner_busy_s = s(m.learner_busy);
  t.checkpoints = m.run_checkpoints;
  return t;
}

bool Trainer::run(const std::atomic<bool>* stop) {
  Impl& m = *impl_;
  const TrainerParams& t = m.config.trainer;
  const int total = t.total_episodes();
  // run()'s time is timed, and every return (or exception) ends the laps.
  struct RunClock {
    Impl& m;
    Clock::time_point start = Clock::now();
    explicit RunClock(Impl& impl) : m(impl) { m.laps.start(); }
    ~RunClock() {
      m.laps.lap(kOther);
      m.laps.on = false;
      m.run_time += Clock::now() - start;
    }
  } run_clock(m);
  auto checkpoint = [&] {
    m.save_checkpoint();
    m.laps.lap(kCheckpoint);
    ++m.run_checkpoints;
  };
  while (m.episode < total) {
    if (stop && stop->load()) {
      checkpoint();
      return false;
    }
    const EpisodeLog log = m.train_episode();
    ++m.episode;
    m.laps.lap(kOther);
    if (m.callbacks.on_episode) m.callbacks.on_episode(log);
    m.progress(log);
    m.laps.lap(kLogging);
    const bool last = m.episode == total;
    if (t.eval_interval > 0 && (m.episode % t.eval_interval == 0 || last)) {
      const EvaluationLog e = m.periodic_evaluation();
      ++m.evaluations;
      m.laps.lap(kEvaluation);
      if (m.callbacks.on_evaluation) m.callbacks.on_evaluation(e);
      m.laps.lap(kLogging);
    }
    if (m.episode % t.checkpoint_interval == 0 || last) checkpoint();
  }
  return true;
}

// ---------------------------------------------------------------------------
// Benchmark support (bench/coopt/bench_trainer).

SideRates measure_side_rates(const CooptConfig& config, std::int64_t steps) {
  if (steps < 1) throw std::invalid_argument("measure_side_rates: steps must be >= 1");
  Trainer::Impl m(config, "", {});
  const TrainerParams& t = config.trainer;
  const int total = t.total_episodes();
  // The last episode may run past `steps` by up to a whole episode.
  std::vector<Transition> record(static_cast<std::size_t>(steps + config.env.task.max_steps + 1));
  for (Transition& tr : record) {
    rl::allocate(motion_spec(config), tr.obs);
    rl::allocate(motion_spec(config), tr.next);
    tr.action.continuous.assign(control::kActionSize, 0.0f);
    tr.action.target.assign(control::kActionSize, 0.0f);  // so that copying a target does not allocate
  }
  m.record = &record;
  SideRates rates;
  Clock::time_point start = Clock::now();
  while (static_cast<std::int64_t>(m.recorded) < steps && m.episode < total) {
    m.train_episode();
    ++m.episode;
  }
  rates.acting_steps = static_cast<std::int64_t>(m.recorded);
  rates.acting_steps_per_s =
      static_cast<double>(m.recorded) / std::chrono::duration<double>(Clock::now() - start).count();

  // The learner alone on those transitions; its first updates start the clock
  // (before learning_starts a step costs only the store).
  rl::Learner& l = *m.learner;
  std::size_t i = 0;
  bool learning = false;
  auto learn = [&](const Transition& tr) {
    l.store(tr.obs, tr.action, tr.reward, tr.next, tr.terminated, tr.truncated);
    int due = l.updates_due();
    learning = learning || due > 0;
    for (; due > 0; --due) l.update();
  };
  while (i < m.recorded && !learning) learn(record[i++]);
  if (!learning)
    throw std::runtime_error("measure_side_rates: " + std::to_string(m.recorded) +
                             " control steps never reached the motion learner's learning_starts; give more steps");
  const std::size_t first_timed = i;
  start = Clock::now();
  while (i < m.recorded) learn(record[i++]);
  rates.learner_steps = static_cast<std::int64_t>(m.recorded - first_timed);
  const double learner_s = std::chrono::duration<double>(Clock::now() - start).count();
  rates.learner_steps_per_s = learner_s > 0 ? static_cast<double>(rates.learner_steps) / learner_s : 0.0;
  return rates;
}

CheckpointCost measure_checkpoint_cost(const CooptConfig& config, const std::string& run_dir,
                                       std::int64_t transitions, std::int64_t new_transitions) {
  Trainer::Impl m(config, run_dir, {});
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  rl::Observation o, next, co, cnext;
  rl::allocate(motion_spec(config), o);
  rl::allocate(motion_spec(config), next);
  rl::allocate(config_spec(config), co);
  rl::allocate(config_spec(config), cnext);
  rl::Action a, ca;
  a.continuous.assign(control::kActionSize, 0.5f);
  if (config.trainer.pilot_labels) a.target.assign(control::kActionSize, 0.5f);
  std::int64_t stored = 0;
  auto fill = [&](std::int64_t n) {
    for (std::int64_t k = 0; k < n; ++k, ++stored) {
      for (float& x : o.vector) x = u(rng);
      for (float& x : o.image) x = u(rng);
      m.learner->store(o, a, u(rng), next, false, false);
      if (m.agent.config && stored % 600 == 0) {
        for (float& x : co.image) x = u(rng);
        ca.discrete = static_cast<int>(stored / 600 % kCandidates);
        m.agent.config->store(co, ca, u(rng), cnext, false, false, 300);
      }
    }
  };
  CheckpointCost cost;
  fill(transitions);
  Clock::time_point start = Clock::now();
  m.save_checkpoint();
  cost.first_s = std::chrono::duration<double>(Clock::now() - start).count();
  fill(new_transitions);
  start = Clock::now();
  m.save_checkpoint();
  cost.next_s = std::chrono::duration<double>(Clock::now() - start).count();
  return cost;
}

// ---------------------------------------------------------------------------

namespace {

// The run's checkpoint, refused when it was written by another configuration.
// Also sets one torch thread per thread: evaluation threads run side by side
// and their results must not depend on how many there are.
CheckpointInfo open_checkpoint_for_evaluation(const CooptConfig& config, const std::string& run_dir) {
  CheckpointInfo info = read_checkpoint_info(run_dir);
  check_same_run(info, config, run_dir);
  rl::set_torch_threads(1, 1);
  return info;
}

// Both networks of a trained run's checkpoint, for greedy acting.
void load_greedy_agent(const CooptConfig& c, const CheckpointInfo& checkpoint, Agent& agent) {
  agent.motion = make_motion(c, 1, true);
  load_checkpoint_file(*agent.motion, (fs::path(checkpoint.directory) / "motion_actor.pt").string());
  agent.config = make_config_model(c, 2);
  if (agent.config) load_checkpoint_file(*agent.config, (fs::path(checkpoint.directory) / "config_model.pt").string());
}

// Greedy episodes of a trained run: one env, scene source and copy of both
// networks (loaded from the checkpoint); one per evaluation thread.
struct GreedyPlayer {
  const CooptConfig& config;
  task::MultiTaskEnv env;
  SceneSource scene;
  Agent agent;
  Buffers buffers;

  GreedyPlayer(const CooptConfig& c, const CheckpointInfo& checkpoint) : config(c), env(c.env), scene(c) {
    load_greedy_agent(c, checkpoint, agent);
    allocate_buffers(c, buffers);
  }

  // Episode `index` of an evaluation of `scenario` (spec from eval_spec).
  EpisodeLog play_episode(const std::string& scenario, const task::EpisodeSpec& spec, int index,
                          const StepObserver* observe = nullptr) {
    EpisodeLog log = play(config, agent, env, scene, spec, false, nullptr, buffers, observe);
    log.episode = index;
    log.scenario = scenario;
    return log;
  }
};

}  // namespace

std::vector<EpisodeLog> evaluate(const CooptConfig& run_config, const std::string& run_dir,
                                 const EvalRequest& request) {
  const CheckpointInfo info = open_checkpoint_for_evaluation(run_config, run_dir);
  CooptConfig config = run_config;  // the identity (text) stays the run's
  if (request.forced_modules != 0) {
    if (request.forced_modules < kMinModules || request.forced_modules > kMaxModules)
      throw std::invalid_argument("evaluate: forced chain of " + std::to_string(request.forced_modules) +
                                  " modules, not in [" + std::to_string(kMinModules) + ", " +
                                  std::to_string(kMaxModules) + "]");
    config.trainer.mode = "fixed";  // play() then drives make_chain(fixed_modules) and no DQN is loaded
    config.trainer.fixed_modules = request.forced_modules;
  }
  std::vector<EpisodeLog> logs(static_cast<std::size_t>(request.episodes));
  std::atomic<int> next{0};
  std::mutex error_mutex;
  std::exception_ptr error;
  auto work = [&] {
    try {
      GreedyPlayer player(config, info);
      for (int i = next++; i < request.episodes; i = next++) {
        const auto spec = eval_spec(config, request.scenario, static_cast<std::uint64_t>(request.seed) + i, i);
        logs[static_cast<std::size_t>(i)] = player.play_episode(request.scenario, spec, i);
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      next = request.episodes;
    }
  };
  const int workers = std::max(1, std::min(request.workers, request.episodes));
  std::vector<std::thread> threads;
  for (int w = 1; w < workers; ++w) threads.emplace_back(work);
  work();
  for (auto& th : threads) th.join();
  if (error) std::rethrow_exception(error);
  return logs;
}

std::uintmax_t export_policy(const CooptConfig& config, const std::string& run_dir,
                             const std::string& out_checkpoint_dir) {
  const CheckpointInfo info = open_checkpoint_for_evaluation(config, run_dir);
  GreedyPlayer player(config, info);
  fs::create_directories(out_checkpoint_dir);
  const fs::path out(out_checkpoint_dir);
  player.agent.motion->save_policy((out / "motion_actor.pt").string());
  if (player.agent.config) player.agent.config->save_policy((out / "config_model.pt").string());
  fs::copy_file(fs::path(info.directory) / "trainer.yaml", out / "trainer.yaml", fs::copy_options::overwrite_existing);
  std::vector<std::string> names{"motion_actor.pt", "trainer.yaml"};
  if (player.agent.config) names.push_back("config_model.pt");
  write_checksums(out_checkpoint_dir, names);  // verified on load like a training checkpoint's
  std::uintmax_t bytes = 0;
  for (const auto& e : fs::directory_iterator(out)) bytes += fs::file_size(e.path());
  return bytes;
}

EpisodeLog play_evaluation_episode(const CooptConfig& config, const std::string& run_dir,
                                   const EvalEpisodeRequest& request, const StepObserver& observer) {
  if (request.index < 0)
    throw std::invalid_argument("play_evaluation_episode: episode index " + std::to_string(request.index) +
                                " < 0 (the stair height cycle starts at episode 0)");
  int obstacles = 0;
  bool mixed = false;
  scenario_settings(request.scenario, obstacles, mixed);  // a bad name throws before the checkpoint loads
  const CheckpointInfo info = open_checkpoint_for_evaluation(config, run_dir);
  GreedyPlayer player(config, info);
  task::EpisodeSpec spec = eval_spec(config, request.scenario,
                                     static_cast<std::uint64_t>(request.first_seed) + request.index, request.index);
  if (request.stair_height_m > 0) spec.stair_height = request.stair_height_m;
  return player.play_episode(request.scenario, spec, request.index, observer ? &observer : nullptr);
}

struct GreedyPolicy::Impl {
  CooptConfig config;
  Agent agent;
  Buffers buffers;
};

GreedyPolicy::GreedyPolicy(const CooptConfig& config, const std::string& run_dir) : impl_(std::make_unique<Impl>()) {
  impl_->config = config;
  load_greedy_agent(config, open_checkpoint_for_evaluation(config, run_dir), impl_->agent);
  allocate_buffers(config, impl_->buffers);
}

GreedyPolicy::~GreedyPolicy() = default;

bool GreedyPolicy::hierarchical() const { return impl_->agent.config != nullptr; }

int GreedyPolicy::decision_image_size() const { return config_spec(impl_->config).image_size(); }

int GreedyPolicy::choose_modules(const float* image, int max_modules, int scene) {
  if (!impl_->agent.config) throw std::logic_error("GreedyPolicy::choose_modules: the run has no configuration model");
  if (max_modules < kMinModules || max_modules > kMaxModules)
    throw std::invalid_argument("max_modules must be in " + std::to_string(kMinModules) + ".." +
                                std::to_string(kMaxModules) + ", got " + std::to_string(max_modules));
  if (scene < 0 || scene > 2) throw std::invalid_argument("scene must be 0, 1 or 2, got " + std::to_string(scene));
  Buffers& b = impl_->buffers;
  std::copy(image, image + b.cobs.image.size(), b.cobs.image.begin());
  fill_config_vector(impl_->config.trainer, candidates()[candidate_of(max_modules)], scene, b, b.cobs);
  impl_->agent.config->act(b.cobs, false, b.caction);
  return modules_of(b.caction.discrete);
}

void GreedyPolicy::act(const float* depth, const float* state, const float* clearance, float* action) {
  Buffers& b = impl_->buffers;
  fill_motion(depth, state, clearance, impl_->config.trainer, b.obs);
  impl_->agent.motion->act(b.obs, false, b.action);
  std::copy(b.action.continuous.begin(), b.action.continuous.end(), action);
}

}  // namespace comorph::coopt
