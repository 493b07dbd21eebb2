// A scripted (not learned) controller for the demo and the physics table. It
// uses ground truth: while the stairs are not climbed it uses stair mode with
// a fixed gait, steering straight up the stairs until module 1 is on the flat
// area; from there it follows a path planned on the known obstacle layout
// (grid distance field), in flat mode once the whole chain is on the top.
#pragma once

#include <array>
#include <optional>
#include <vector>

#include "control/motion_modes.hpp"
#include "task/multitask_env.hpp"

namespace comorph::task {

struct StairGait {  // stair-mode action (Eq. 4/5 inputs), held while climbing
  float speed = 1.0f;       // a0
  float amp_front = 0.0f;   // a2 (-1 = no wave)
  float phase = 0.5f;       // a3
  float amp_back = 0.0f;    // a4
};

struct PilotParams {
  StairGait gait;               // used in stair mode (unless gait_by_modules has one for the chain)
  // Per chain length (index = modules), a gait of its own where set. One gait
  // does not suit every length: the wave lag that climbs with 2, 4 or 6
  // modules stalls 3 modules on the first riser (searched_stair_gaits()).
  std::array<std::optional<StairGait>, kMaxModules + 1> gait_by_modules{};
  double heading_gain = 2.5;    // a1 per rad of heading error
  double lookahead = 0.6;       // m along the planned path
  double clearance = 0.40;      // m, obstacles inflated by this when planning
  double slow_turn_error = 0.6; // rad: above this heading error the robot turns before driving
};

// The pilot with the stair gaits of a search over a0 x a2=a4 x a3 per chain
// length (docs/results.md): the shared gait, and 3 modules' own.
PilotParams searched_stair_gaits();

class ScriptedPilot {
 public:
  explicit ScriptedPilot(PilotParams params = {}) : p_(params) {}
  // Plans on the env's current scene; call after env.reset().
  void plan(const MultiTaskEnv& env);
  // The action and mode for the env's current state.
  void act(const MultiTaskEnv& env, float action[control::kActionSize], control::MotionMode& mode) const;
  PilotParams& params() { return p_; }

 private:
  PilotParams p_;
  // Distance-to-target field on a grid over the flat area (m; < 0 blocked).
  std::vector<double> field_;
  int nx_ = 0, ny_ = 0;
  double x0_ = 0, y0_ = 0, cell_ = 0.05;
};

}  // namespace comorph::task
