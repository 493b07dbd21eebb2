// The multi-task episode (paper Fig. 8): climb the stairs, cross the obstacle
// field, reach the target. MuJoCo-style split: the EnvConfig and the compiled
// models are read-only; the env holds the mutable episode state. No torch:
// observations are plain float buffers the learner copies into tensors.
//
// Per control step (32 ms): action (5 floats in [-1, 1]) + motion mode ->
// Eq. 4/5 motor commands -> 16 x mj_step -> sensors, termination, R1.
// The hot path does not allocate; reset() and reconfigure() never recompile
// (models are compiled once per configuration and cached).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "control/motion_modes.hpp"
#include "morphology/configuration.hpp"
#include "sim/mjcf.hpp"
#include "sim/scene.hpp"
#include "sim/world.hpp"
#include "task/env_config.hpp"

namespace comorph::task {

enum class Termination : int {
  none = 0,
  success,           // module 1 within target_radius of the target (r_g)
  collision,         // a robot geom touched an obstacle (r_u)
  overturned,        // a module tilted past overturn_up_z (r_u)
  left_area,         // left the stair lane / flat area sideways or fell off it (r_u)
  battery_empty,     // a module's battery is empty (r_u)
  physics_unstable,  // NaN or a MuJoCo bad-qacc/qpos/qvel warning (r_u)
  step_cap,          // max_steps reached (truncation, no r_u)
};
constexpr auto enum_names(Termination) {
  using T = Termination;
  return std::array{EnumName{T::none, "none"},
                    EnumName{T::success, "success"},
                    EnumName{T::collision, "collision"},
                    EnumName{T::overturned, "overturned"},
                    EnumName{T::left_area, "left_area"},
                    EnumName{T::battery_empty, "battery_empty"},
                    EnumName{T::physics_unstable, "physics_unstable"},
                    EnumName{T::step_cap, "step_cap"}};
}
// The name of episodes.csv's termination column.
inline const char* termination_name(Termination t) { return name_at(t); }

struct EpisodeSpec {
  std::uint64_t seed = 0;    // draws the scene (stair height, obstacles, target, start noise)
  Configuration configuration = make_chain(4);  // the robot; the controller drives chains only
  double stair_height = 0;   // m; <= 0 draws it from the seed
  int obstacles = -1;        // K; < 0 takes SceneParams::obstacles
  sim::Variant variant = sim::Variant::standard;
};

struct StepOutcome {
  double reward = 0;          // R1 of this step (Eq. 6)
  bool terminated = false;    // success or failure
  bool truncated = false;     // step cap
  Termination reason = Termination::none;
  int scene_label = 0;        // ground truth after the step (sim::SceneLabel)
  bool stairs_climbed_now = false;  // the r_s event happened in this step
  double energy_J = 0;        // J drawn in this step
  double progress_m = 0;      // dD: m closer to the current goal
  double cos_beta = 0;        // heading term of R1
};

// The objective terms of the episode so far (Eq. 1).
struct EpisodeMetrics {
  int steps = 0;                 // control steps taken
  double time_s = 0;             // simulated s
  double energy_J = 0;           // J drawn by all modules (shed ones included)
  double initial_distance_m = 0; // start -> target, horizontal
  double distance_done_m = 0;    // initial - current distance to the target, >= 0
  double T = 0;                  // time_s / ObjectiveWeights::t_max_s
  double E = 0;                  // energy_J / ObjectiveWeights::energy_scale_J
  double D = 0;                  // distance_done_m / initial_distance_m, in [0, 1]
  double F = 0;                  // Eq. 1 with TaskParams::objective
};

// Layout of the state vector (floats). Modules beyond the chain are zero and masked.
namespace obs {
inline constexpr int kBattery = 0;       // 1: mean remaining battery fraction of the modules, 0..1
inline constexpr int kPosition = 1;      // 3: module 1 position x, y, z (m, scene frame)
inline constexpr int kVelocity = 4;      // 2: module 1 velocity vx, vy (m/s, scene frame)
inline constexpr int kPrevReward = 6;    // 1: R1 of the previous step
inline constexpr int kPrevAction = 7;    // 5: previous action
inline constexpr int kDistances = 12;    // 20: left, right distance of module k at 12 + 2k (0..1 of range)
inline constexpr int kModuleMask = 32;   // 10: 1 for modules present
inline constexpr int kGoal = 42;         // 3: cos, sin of the goal bearing relative to the heading; distance (m)
inline constexpr int kMode = 45;         // 1: motion mode of the last step (0 flat, 1 stair)
inline constexpr int kStateSize = 46;
}  // namespace obs

// What the env observes and takes: shapes and bounds, declared here so that
// learners and bindings read them instead of assembling them.
struct EnvSpec {
  int depth_channels = 1;  // depth(): depth_channels x depth_height x depth_width, row-major
  int depth_height = 0;
  int depth_width = 0;
  float depth_low = 0.01f;  // depth() and clearance(): fraction of the sensor's range
  float depth_high = 1.0f;
  int state_size = obs::kStateSize;  // state(): unbounded (m, m/s, R1; layout in task::obs)
  int clearance_size = 0;            // clearance()
  int decision_depth_height = 0;     // render_decision_depth(): height x width
  int decision_depth_width = 0;
  int action_size = control::kActionSize;  // step(): action_size floats in [action_low, action_high]
  float action_low = -1.0f;
  float action_high = 1.0f;
  int min_modules = kMinModules;     // chain lengths of EpisodeSpec::configuration and reconfigure()
  int max_modules = kMaxModules;
};

class MultiTaskEnv {
 public:
  static EnvSpec spec(const EnvConfig& config);
  EnvSpec spec() const { return spec(config_); }

  explicit MultiTaskEnv(const EnvConfig& config, std::shared_ptr<sim::ModelCache> cache = nullptr);

  // New episode; observations are valid after it.
  void reset(const EpisodeSpec& spec);
  // One control step with the given motion mode. Throws std::logic_error after the episode ended.
  const StepOutcome& step(const float* action, control::MotionMode mode);
  // The same with default_mode() (ground truth) for scripted use.
  const StepOutcome& step(const float* action) { return step(action, default_mode()); }
  // Sheds modules: `part` must be a sub-configuration of configuration()
  // (throws std::invalid_argument naming the fault); carries the kept modules' state exactly.
  void reconfigure(const Configuration& part);

  // Ground truth: stair until the whole chain is on the top of the stairs, then flat.
  control::MotionMode default_mode() const;

  // ---- observations (valid until the next step/reset) ----
  const float* depth() const { return depth_.data(); }  // 1 x H x W, row-major, [0.01, 1]
  int depth_width() const { return config_.robot.depth_width; }
  int depth_height() const { return config_.robot.depth_height; }
  const float* state() const { return state_.data(); }  // obs::kStateSize floats
  // What is straight ahead: per depth-image column, the nearest depth over the
  // rows that look above the horizon (they never see the floor a robot stands
  // on, so only obstacles, risers, the target post or 1 = nothing within range).
  // depth_width() floats in [0.01, 1], column 0 at the left.
  // With RobotParams::scan_columns > 0 it is the obstacle scan instead (a level
  // fan of range rays, World::render_scan): clearance_width() floats.
  const float* clearance() const { return clearance_.data(); }
  int clearance_width() const { return clearance_width(config_.robot); }
  static int clearance_width(const sim::RobotParams& r) { return r.scan_columns > 0 ? r.scan_columns : r.depth_width; }
  // The decision camera's image (decision_depth_height() x decision_depth_width()),
  // rendered on request: the configuration model reads it only when it decides.
  void render_decision_depth(float* out) const { world_.render_decision_depth(out); }
  int decision_depth_width() const { return config_.robot.decision_depth_width; }
  int decision_depth_height() const { return config_.robot.decision_depth_height; }
  int scene_label() const { return label_; }           // sim::SceneLabel of module 1's position

  // ---- episode bookkeeping for R2 and evaluation ----
  EpisodeMetrics metrics() const;
  bool on_stairs() const { return on_stairs_; }             // some module on the stairs, not yet climbed
  bool stairs_climbed() const { return climbed_step_ >= 0; }
  int stairs_climbed_step() const { return climbed_step_; }  // control step of the r_s event, -1 if not yet
  double stairs_energy() const { return stairs_energy_; }   // J drawn while on_stairs (E_c)
  double stair_height() const { return world_.layout().stair_height; }
  int modules() const { return world_.modules(); }
  const Configuration& configuration() const { return world_.configuration(); }
  int initial_modules() const { return initial_modules_; }
  int step_count() const { return steps_; }
  bool done() const { return done_; }
  const StepOutcome& last() const { return result_; }
  control::MotionMode mode() const { return mode_; }
  void goal(double& x, double& y) const;                    // current goal (m)
  double target_distance() const;                          // m, module 1 -> the target, horizontal

  const sim::World& world() const { return world_; }
  sim::World& mutable_world() { return world_; }  // tools and tests (e.g. depth from arbitrary poses)
  const EnvConfig& config() const { return config_; }

 private:
  void update_observation();
  double goal_distance() const;
  bool check_climbed() const;
  bool any_module_on_stairs() const;
  Termination check_failure(const sim::PhysicsStepInfo& info) const;

  EnvConfig config_;
  sim::World world_;
  control::MotorCommand command_;
  std::array<double, sim::kActuatorsPerModule * kMaxModules> ctrl_{};
  std::vector<float> depth_;
  std::vector<float> clearance_;
  int horizon_rows_ = 1;  // depth rows whose centre looks above the horizon (level camera)
  std::array<float, obs::kStateSize> state_{};
  std::array<float, control::kActionSize> prev_action_{};
  std::array<float, 2 * kMaxModules> distances_{};
  StepOutcome result_;
  control::MotionMode mode_ = control::MotionMode::flat;
  int initial_modules_ = 0;
  int steps_ = 0;
  int label_ = 0;
  int climbed_step_ = -1;
  bool on_stairs_ = false;
  bool done_ = false;
  double stairs_energy_ = 0;
  double initial_distance_ = 0;
};

}  // namespace comorph::task
