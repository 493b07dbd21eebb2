#include "task/multitask_env.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace comorph::task {

EnvSpec MultiTaskEnv::spec(const EnvConfig& config) {
  const sim::RobotParams& r = config.robot;
  EnvSpec s;
  s.depth_height = r.depth_height;
  s.depth_width = r.depth_width;
  s.clearance_size = clearance_width(r);
  s.decision_depth_height = r.decision_depth_height;
  s.decision_depth_width = r.decision_depth_width;
  return s;
}

MultiTaskEnv::MultiTaskEnv(const EnvConfig& config, std::shared_ptr<sim::ModelCache> cache)
    : config_(config), world_(config.robot, config.scene, std::move(cache)) {
  const sim::RobotParams& r = config_.robot;
  depth_.assign(std::size_t(r.depth_width) * r.depth_height, 1.0f);
  clearance_.assign(std::size_t(clearance_width(r)), 1.0f);
  horizon_rows_ = world_.depth_rows_above_horizon();
}

void MultiTaskEnv::reset(const EpisodeSpec& spec) {
  const sim::SceneLayout layout =
      sim::generate_scene(config_.scene, spec.seed, spec.stair_height, spec.obstacles, spec.variant);
  world_.reset(layout, spec.configuration);
  initial_modules_ = world_.modules();
  steps_ = 0;
  climbed_step_ = -1;
  done_ = false;
  stairs_energy_ = 0;
  prev_action_.fill(0.0f);
  result_ = StepOutcome{};
  mode_ = default_mode();
  const double* head = world_.module_pos(0);
  initial_distance_ = std::hypot(layout.target_x - head[0], layout.target_y - head[1]);
  on_stairs_ = any_module_on_stairs();
  update_observation();
}

void MultiTaskEnv::goal(double& x, double& y) const {
  const sim::SceneLayout& s = world_.layout();
  if (stairs_climbed()) {
    x = s.target_x;
    y = s.target_y;
  } else {
    // Far enough that the whole chain is on the top when module 1 reaches it.
    x = s.platform_x + config_.task.stair_goal_offset + world_.modules() * config_.robot.module_length;
    y = 0.0;
  }
}

double MultiTaskEnv::goal_distance() const {
  double gx, gy;
  goal(gx, gy);
  const double* head = world_.module_pos(0);
  return std::hypot(gx - head[0], gy - head[1]);
}

double MultiTaskEnv::target_distance() const {
  const double* head = world_.module_pos(0);
  return std::hypot(world_.layout().target_x - head[0], world_.layout().target_y - head[1]);
}

control::MotionMode MultiTaskEnv::default_mode() const {
  return stairs_climbed() ? control::MotionMode::flat : control::MotionMode::stair;
}

bool MultiTaskEnv::check_climbed() const {
  const sim::SceneLayout& s = world_.layout();
  const double min_z = s.platform_z + 0.5 * config_.robot.wheel_radius;
  for (int k = 0; k < world_.modules(); ++k) {
    const double* p = world_.module_pos(k);
    if (p[0] < s.platform_x + 0.02 || p[2] < min_z) return false;
  }
  return true;
}

bool MultiTaskEnv::any_module_on_stairs() const {
  if (stairs_climbed()) return false;
  const double reach = 0.5 * config_.robot.module_length + config_.robot.wheel_radius;
  for (int k = 0; k < world_.modules(); ++k) {
    const double x = world_.module_pos(k)[0];
    if (x > -reach && x < world_.layout().platform_x + reach) return true;
  }
  return false;
}

Termination MultiTaskEnv::check_failure(const sim::PhysicsStepInfo& info) const {
  if (info.instability != sim::Instability::none) return Termination::physics_unstable;
  if (info.obstacle_contact) return Termination::collision;
  const sim::SceneLayout& s = world_.layout();
  const sim::SceneParams& sp = config_.scene;
  for (int k = 0; k < world_.modules(); ++k)
    if (world_.module_up_z(k) < config_.task.overturn_up_z) return Termination::overturned;
  for (int k = 0; k < world_.modules(); ++k) {
    const double* p = world_.module_pos(k);
    const bool before_area = p[0] < s.platform_x;
    const double half_width = before_area ? 0.5 * sp.stair_width : 0.5 * sp.area_width;
    if (std::abs(p[1]) > half_width || p[0] > s.area_end_x ||
        p[0] < s.start_x - config_.task.start_zone_length)
      return Termination::left_area;
    // Fell off an edge: well below the surface under it.
    if (p[2] < sim::floor_height(s, p[0], p[1]) - 0.05) return Termination::left_area;
  }
  for (int k = 0; k < world_.modules(); ++k)
    if (world_.battery_fraction(k) <= 0.0) return Termination::battery_empty;
  return Termination::none;
}

const StepOutcome& MultiTaskEnv::step(const float* action, control::MotionMode mode) {
  if (done_) throw std::logic_error("MultiTaskEnv::step after the episode ended; call reset()");
  const int n = world_.modules();
  const double goal_before = goal_distance();
  control::compute_command(config_.motion, mode, action, world_.time(), n, config_.robot.wheel_radius,
                           config_.robot.wheel_max_speed, command_);
  control::command_to_ctrl(command_, n, ctrl_.data());
  const sim::PhysicsStepInfo info = world_.step_control(ctrl_.data());
  ++steps_;
  mode_ = mode;

  StepOutcome r;
  r.energy_J = info.energy_J;
  if (on_stairs_) stairs_energy_ += info.energy_J;
  const double* head = world_.module_pos(0);
  r.progress_m = goal_before - goal_distance();
  {
    double gx, gy;
    goal(gx, gy);
    const double vx = world_.data()->qvel[0], vy = world_.data()->qvel[1];
    const double speed = std::hypot(vx, vy), dist = std::hypot(gx - head[0], gy - head[1]);
    r.cos_beta = speed > 1e-3 && dist > 1e-9 ? (vx * (gx - head[0]) + vy * (gy - head[1])) / (speed * dist) : 0.0;
  }
  if (!stairs_climbed() && check_climbed()) {
    climbed_step_ = steps_;
    r.stairs_climbed_now = true;
  }
  on_stairs_ = any_module_on_stairs();

  const R1Params& p = config_.task.r1;
  r.reason = check_failure(info);
  double r_u = 0, r_g = 0;
  if (r.reason != Termination::none) {
    r.terminated = true;
    r_u = p.r_u;
  } else if (std::hypot(head[0] - world_.layout().target_x, head[1] - world_.layout().target_y) <=
             config_.scene.target_radius) {
    r.terminated = true;
    r.reason = Termination::success;
    r_g = p.r_g;
  } else if (steps_ >= config_.task.max_steps) {
    r.truncated = true;
    r.reason = Termination::step_cap;
  }
  const double tau4 = 1.0 + p.alpha_g * (1.0 - steps_ / p.t_sum);
  r.reward = p.tau1 * r.progress_m + p.tau2 * r.cos_beta + p.tau3 * r_u + tau4 * r_g;
  done_ = r.terminated || r.truncated;
  for (int i = 0; i < control::kActionSize; ++i) prev_action_[i] = std::clamp(action[i], -1.0f, 1.0f);
  result_ = r;
  update_observation();
  result_.scene_label = label_;
  return result_;
}

void MultiTaskEnv::reconfigure(const Configuration& part) {
  if (done_) throw std::logic_error("MultiTaskEnv::reconfigure after the episode ended");
  world_.reconfigure(part);
  on_stairs_ = any_module_on_stairs();
  update_observation();
}

void MultiTaskEnv::update_observation() {
  const int n = world_.modules();
  world_.render_depth(depth_.data());
  if (config_.robot.scan_columns > 0) {
    world_.render_scan(clearance_.data());
  } else {
    const int w = depth_width();
    for (int j = 0; j < w; ++j) {
      float nearest = 1.0f;
      for (int i = 0; i < horizon_rows_; ++i) nearest = std::min(nearest, depth_[std::size_t(i) * w + j]);
      clearance_[std::size_t(j)] = nearest;
    }
  }
  world_.read_distances(distances_.data());
  const double* head = world_.module_pos(0);
  label_ = sim::scene_label(config_.scene, world_.layout(), head[0], head[1]);

  float* s = state_.data();
  double battery = 0;
  for (int k = 0; k < n; ++k) battery += world_.battery_fraction(k);
  s[obs::kBattery] = float(battery / n);
  for (int a = 0; a < 3; ++a) s[obs::kPosition + a] = float(head[a]);
  s[obs::kVelocity] = float(world_.data()->qvel[0]);
  s[obs::kVelocity + 1] = float(world_.data()->qvel[1]);
  s[obs::kPrevReward] = float(result_.reward);
  for (int i = 0; i < control::kActionSize; ++i) s[obs::kPrevAction + i] = prev_action_[i];
  for (int k = 0; k < kMaxModules; ++k) {
    const bool present = k < n;
    s[obs::kDistances + 2 * k] = present ? distances_[2 * k] : 0.0f;
    s[obs::kDistances + 2 * k + 1] = present ? distances_[2 * k + 1] : 0.0f;
    s[obs::kModuleMask + k] = present ? 1.0f : 0.0f;
  }
  double gx, gy;
  goal(gx, gy);
  const double bearing = std::atan2(gy - head[1], gx - head[0]) - world_.heading();
  s[obs::kGoal] = float(std::cos(bearing));
  s[obs::kGoal + 1] = float(std::sin(bearing));
  s[obs::kGoal + 2] = float(std::hypot(gx - head[0], gy - head[1]));
  s[obs::kMode] = float(int(mode_));
}

EpisodeMetrics MultiTaskEnv::metrics() const {
  EpisodeMetrics m;
  m.steps = steps_;
  m.time_s = steps_ * config_.robot.control_period;
  m.energy_J = world_.energy_used();
  m.initial_distance_m = initial_distance_;
  m.distance_done_m = std::max(0.0, initial_distance_ - target_distance());
  const ObjectiveWeights& w = config_.task.objective;
  m.T = m.time_s / w.t_max_s;
  m.E = m.energy_J / w.energy_scale_J;
  m.D = initial_distance_ > 0 ? std::clamp(m.distance_done_m / initial_distance_, 0.0, 1.0) : 0.0;
  m.F = objective(w, m.time_s, m.energy_J, m.D);
  return m;
}

}  // namespace comorph::task
