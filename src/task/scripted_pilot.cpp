#include "task/scripted_pilot.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <queue>
#include <stdexcept>

namespace comorph::task {
namespace {
constexpr std::size_t kMaxScanRays = 256;  // RobotParams::scan_columns' upper bound (params_yaml)

double wrap(double a) {
  while (a > M_PI) a -= 2 * M_PI;
  while (a < -M_PI) a += 2 * M_PI;
  return a;
}
}  // namespace

void ScriptedPilot::plan(const MultiTaskEnv& env) {
  field_.clear();
  if (p_.flat_steering == FlatSteering::scan) return;  // steers by the scan: no path to plan
  const sim::SceneLayout& s = env.world().layout();
  const sim::SceneParams& sp = env.config().scene;
  x0_ = s.platform_x;
  y0_ = -0.5 * sp.area_width;
  nx_ = int(std::ceil(sp.area_length / cell_)) + 1;
  ny_ = int(std::ceil(sp.area_width / cell_)) + 1;
  field_.assign(std::size_t(nx_) * ny_, -1.0);
  std::vector<char> blocked(field_.size(), 0);
  for (int i = 0; i < nx_; ++i)
    for (int j = 0; j < ny_; ++j) {
      const double x = x0_ + i * cell_, y = y0_ + j * cell_;
      bool b = std::abs(y) > 0.5 * sp.area_width - 0.3;
      for (const sim::Box& o : s.obstacles)
        b = b || (std::abs(x - o.x) < o.hx + p_.clearance && std::abs(y - o.y) < o.hy + p_.clearance);
      blocked[std::size_t(i) * ny_ + j] = b;
    }
  // Dijkstra from the target, 8-connected.
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  const int ti = std::clamp(int(std::lround((s.target_x - x0_) / cell_)), 0, nx_ - 1);
  const int tj = std::clamp(int(std::lround((s.target_y - y0_) / cell_)), 0, ny_ - 1);
  field_[std::size_t(ti) * ny_ + tj] = 0;
  queue.push({0, ti * ny_ + tj});
  while (!queue.empty()) {
    const auto [d, id] = queue.top();
    queue.pop();
    if (d > field_[id]) continue;
    const int i = id / ny_, j = id % ny_;
    for (int di = -1; di <= 1; ++di)
      for (int dj = -1; dj <= 1; ++dj) {
        const int a = i + di, b = j + dj;
        if ((!di && !dj) || a < 0 || b < 0 || a >= nx_ || b >= ny_) continue;
        const int n = a * ny_ + b;
        if (blocked[n]) continue;
        const double nd = d + cell_ * ((di && dj) ? M_SQRT2 : 1.0);
        if (field_[n] < 0 || nd < field_[n]) {
          field_[n] = nd;
          queue.push({nd, n});
        }
      }
  }
}

void ScriptedPilot::act(const MultiTaskEnv& env, float a[control::kActionSize],
                        control::MotionMode& mode) const {
  const double* head = env.world().module_pos(0);
  const double heading = env.world().heading();
  mode = env.default_mode();
  double gx, gy;
  env.goal(gx, gy);
  const bool climbing = !env.stairs_climbed();
  // Steer along the planned path once module 1 is on the flat area (a long
  // chain's head reaches the obstacles while its tail is still climbing).
  const bool on_top = head[0] > env.world().layout().platform_x + 0.3;
  const bool scan_steering = on_top && p_.flat_steering == FlatSteering::scan;
  if (scan_steering) {
    const sim::SceneLayout& s = env.world().layout();
    const double goal_bearing = wrap(std::atan2(s.target_y - head[1], s.target_x - head[0]) - heading);
    const double bearing = scan_target_bearing(env, goal_bearing, std::hypot(s.target_x - head[0], s.target_y - head[1]));
    gx = head[0] + std::cos(heading + bearing);
    gy = head[1] + std::sin(heading + bearing);
  } else if (on_top && !field_.empty()) {
    // Walk down the distance field from module 1's cell for `lookahead` metres.
    int i = std::clamp(int(std::lround((head[0] - x0_) / cell_)), 0, nx_ - 1);
    int j = std::clamp(int(std::lround((head[1] - y0_) / cell_)), 0, ny_ - 1);
    if (field_[std::size_t(i) * ny_ + j] < 0) {
      // Inside an inflated obstacle: start from the nearest cell with a path.
      int best_i = i, best_j = j, best_d2 = 1 << 30;
      const int r = int(1.0 / cell_);
      for (int di = -r; di <= r; ++di)
        for (int dj = -r; dj <= r; ++dj) {
          const int x = i + di, y = j + dj;
          if (x < 0 || y < 0 || x >= nx_ || y >= ny_ || field_[std::size_t(x) * ny_ + y] < 0) continue;
          if (di * di + dj * dj < best_d2) best_d2 = di * di + dj * dj, best_i = x, best_j = y;
        }
      i = best_i;
      j = best_j;
    }
    const int hops = int(p_.lookahead / cell_);
    for (int h = 0; h < hops; ++h) {
      int bi = i, bj = j;
      double best = field_[std::size_t(i) * ny_ + j];
      if (best < 0) best = 1e9;
      for (int di = -1; di <= 1; ++di)
        for (int dj = -1; dj <= 1; ++dj) {
          const int x = i + di, y = j + dj;
          if (x < 0 || y < 0 || x >= nx_ || y >= ny_) continue;
          const double f = field_[std::size_t(x) * ny_ + y];
          if (f >= 0 && f < best) best = f, bi = x, bj = y;
        }
      if (bi == i && bj == j) break;
      i = bi;
      j = bj;
    }
    gx = x0_ + i * cell_;
    gy = y0_ + j * cell_;
    if (std::hypot(env.world().layout().target_x - head[0], env.world().layout().target_y - head[1]) < p_.lookahead) {
      gx = env.world().layout().target_x;
      gy = env.world().layout().target_y;
    }
  }
  if (!on_top && p_.stair_steering == StairSteering::scan) {
    // Along the stairs in its lane (back towards the middle beyond
    // stair_lane_m), around an obstacle the scan shows ahead.
    const double lane_y = std::clamp(head[1], -p_.stair_lane_m, p_.stair_lane_m);
    const double bearing = stair_target_bearing(env, wrap(std::atan2(lane_y - head[1], 1.0) - heading));
    gx = head[0] + std::cos(heading + bearing);
    gy = head[1] + std::sin(heading + bearing);
  } else if (!on_top) {  // straight up the middle of the stairs
    gx = head[0] + 1.0;
    gy = 0.0;
  }
  const double error = wrap(std::atan2(gy - head[1], gx - head[0]) - heading);
  a[1] = float(std::clamp(p_.heading_gain * error, -1.0, 1.0));
  if (climbing) {
    const int n = env.world().modules();
    const StairGait& g = p_.gait_by_modules[std::size_t(n)].value_or(p_.gait);
    a[0] = g.speed;
    a[2] = g.amp_front;
    a[3] = g.phase;
    a[4] = g.amp_back;
  } else {
    const double turn = std::abs(error);
    const double slow = scan_steering ? p_.scan_slow_turn_error : p_.slow_turn_error;
    a[0] = float(turn > slow ? 0.0 : std::cos(turn) * (1.0 - turn / slow * 0.7));
    a[2] = -1.0f;
    a[3] = 0.0f;
    a[4] = -1.0f;
  }
}

double ScriptedPilot::scan_target_bearing(const MultiTaskEnv& env, double goal_bearing, double goal_distance) const {
  const sim::RobotParams& robot = env.config().robot;
  if (robot.scan_columns <= 0)
    throw std::logic_error("ScriptedPilot: flat_steering scan needs env.robot.scan_columns > 0");
  // The goal outside the fan: turn towards it (nothing is known there).
  if (std::abs(goal_bearing) > 0.5 * robot.scan_fov_x) return goal_bearing;
  std::array<bool, kMaxScanRays> every;
  every.fill(true);
  return open_bearing(env, every.data(), goal_bearing, std::min(p_.scan_lookahead_m, goal_distance));
}

double ScriptedPilot::stair_target_bearing(const MultiTaskEnv& env, double goal_bearing) const {
  const sim::RobotParams& robot = env.config().robot;
  if (robot.scan_columns <= 0)
    throw std::logic_error("ScriptedPilot: stair_steering scan needs env.robot.scan_columns > 0");
  const int rays = env.clearance_width();
  if (rays > int(kMaxScanRays)) throw std::logic_error("ScriptedPilot: more than 256 scan rays");
  const double fov = robot.scan_fov_x, step = fov / rays;
  const float* scan = env.clearance();
  auto x_of = [&](int j) { return scan[j] * robot.depth_max_range * std::cos(0.5 * fov - step * (j + 0.5)); };
  auto y_of = [&](int j) { return scan[j] * robot.depth_max_range * std::sin(0.5 * fov - step * (j + 0.5)); };
  // Runs of adjacent hits whose points are within stair_point_gap_m of the
  // previous one; a run of 2+ rays spanning at most stair_obstacle_max_m counts.
  std::array<bool, kMaxScanRays> obstacle;
  obstacle.fill(false);
  int start = -1;
  for (int j = 0; j <= rays; ++j) {
    const bool joins = j < rays && scan[j] < 1.0f && start >= 0 &&
                       std::hypot(x_of(j) - x_of(j - 1), y_of(j) - y_of(j - 1)) <= p_.stair_point_gap_m;
    if (joins) continue;
    if (start >= 0 && j - start >= 2 &&
        std::hypot(x_of(j - 1) - x_of(start), y_of(j - 1) - y_of(start)) <= p_.stair_obstacle_max_m)
      for (int k = start; k < j; ++k) obstacle[std::size_t(k)] = true;
    start = j < rays && scan[j] < 1.0f ? j : -1;
  }
  if (std::abs(goal_bearing) > 0.5 * fov) return goal_bearing;
  return open_bearing(env, obstacle.data(), goal_bearing, p_.stair_lookahead_m);
}

double ScriptedPilot::open_bearing(const MultiTaskEnv& env, const bool* counts, double goal_bearing,
                                   double lookahead) const {
  const sim::RobotParams& robot = env.config().robot;
  const int rays = env.clearance_width();
  if (rays > int(kMaxScanRays)) throw std::logic_error("ScriptedPilot: more than 256 scan rays");
  const double fov = robot.scan_fov_x, step = fov / rays;
  const float* scan = env.clearance();  // fraction of depth_max_range, ray 0 at the left
  const double last_turn = env.state()[obs::kPrevAction + 1];
  auto bearing_of = [&](int j) { return 0.5 * fov - step * (j + 0.5); };
  // Open: no counted scanned point in the corridor of half-width
  // scan_corridor_m ahead along the bearing, up to the lookahead.
  auto open = [&](double bearing) {
    for (int k = 0; k < rays; ++k) {
      if (!counts[k]) continue;
      const double r = scan[k] * robot.depth_max_range, d = bearing_of(k) - bearing;
      const double along = r * std::cos(d), across = std::abs(r * std::sin(d));
      if (scan[k] < 1.0f && along > 0 && along < lookahead && across < p_.scan_corridor_m) return false;
    }
    return true;
  };
  if (open(goal_bearing)) return goal_bearing;
  double best = 0, best_cost = 1e9;
  for (int j = 0; j < rays; ++j) {
    const double bearing = bearing_of(j);
    if (!open(bearing)) continue;
    double cost = std::abs(bearing - goal_bearing);
    if (bearing * last_turn < 0 && std::abs(bearing) > step && std::abs(last_turn) > p_.scan_committed_turn)
      cost += p_.scan_hysteresis_rad;
    if (cost < best_cost) best_cost = cost, best = bearing;
  }
  if (best_cost < 1e9) return best;
  // Nothing open: turn in place towards the side the last turn went (left when none).
  return last_turn < 0 ? -0.5 * fov : 0.5 * fov;
}

PilotParams searched_stair_gaits() {
  // A search over a0 in {1, 0.6} x a2 = a4 in {1, 0} x a3 in {-0.5, -0.2, 0.2, 0.5}
  // for 3, 4, 5, 7 and 9 modules (3 seeds per height), beside the physics table's
  // even lengths: full amplitude with wave lag -0.5 is the best (or as good as any)
  // everywhere but at 3 modules, which it stalls on the first riser (0 of 3 at
  // 0.04 m), where lag +0.2 climbs 3 of 3. 7 modules climb 0.08 m with no gait of
  // the grid, and 3 modules never climb 0.06 m (without noise on the gait).
  PilotParams p;
  p.gait = {1.0f, 1.0f, -0.5f, 1.0f};
  p.gait_by_modules[3] = StairGait{1.0f, 1.0f, 0.2f, 1.0f};
  return p;
}

}  // namespace comorph::task
