// A scripted (not learned) controller for the demo, the physics table and the
// trainer's demonstrations and labels. While the stairs are not climbed it
// uses stair mode with a fixed gait, steering straight up the stairs until
// module 1 is on the flat area. From there, in flat mode once the whole chain
// is on the top, it steers either along a path planned on the known obstacle
// layout (FlatSteering::planned, ground truth) or towards the free direction
// of the obstacle scan nearest the goal (FlatSteering::scan: only what the
// motion model observes, so its labels are a function of the model's input).
#pragma once

#include <vector>

#include "control/motion_modes.hpp"
#include "task/pilot_params.hpp"
#include "task/multitask_env.hpp"

namespace comorph::task {

class ScriptedPilot {
 public:
  explicit ScriptedPilot(PilotParams params = {}) : p_(params) {}
  // Plans on the env's current scene; call after env.reset().
  void plan(const MultiTaskEnv& env);
  // The action and mode for the env's current state.
  void act(const MultiTaskEnv& env, float action[control::kActionSize], control::MotionMode& mode) const;
  PilotParams& params() { return p_; }

 private:
  // Bearing (rad, + left of module 1's heading) to aim at on the flat area
  // from the obstacle scan, given the goal's bearing and distance.
  double scan_target_bearing(const MultiTaskEnv& env, double goal_bearing, double goal_distance) const;
  // The same on the stairs, where only runs of rays shaped like an obstacle
  // count (PilotParams::stair_steering); the goal is the stairs' direction.
  double stair_target_bearing(const MultiTaskEnv& env, double goal_bearing) const;
  // Bearing to aim at among the scan's rays for which `counts` is true.
  double open_bearing(const MultiTaskEnv& env, const bool* counts, double goal_bearing, double lookahead) const;

  PilotParams p_;
  // Distance-to-target field on a grid over the flat area (m; < 0 blocked).
  std::vector<double> field_;
  int nx_ = 0, ny_ = 0;
  double x0_ = 0, y0_ = 0, cell_ = 0.05;
};

}  // namespace comorph::task
