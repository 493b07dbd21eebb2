// MJCF of the robot and the scene, built from the robot's configuration
// (a Configuration of src/morphology), never from a count. The chain is a kinematic tree:
// module 1 has the free joint; module k+1 hangs from module k through two
// pitch hinges (module k's back plate "back<k>" and module k+1's front plate
// "front<k+1>"). Body/joint order makes the state of modules 1..M a prefix of
// qpos/qvel for any chain longer than M (reconfiguration relies on it):
//   qpos = [root(7), wheel_l1, wheel_r1, front1, back1, front2, wheel_l2, wheel_r2, back2, ...]
//   ctrl = per module k (0-based): 4k+0 wheel_l, 4k+1 wheel_r, 4k+2 front hinge, 4k+3 back hinge
// Geom groups: 0 = scene (seen by the depth camera and distance sensors),
// 1 = robot, 2 = decoration, 5 = unused obstacle slots.
// Contacts: robot-scene only (no robot self-collision: adjacent modules are
// joined by the hinges and the chain cannot fold onto itself within the
// hinge range; scene-scene pairs are static).
#pragma once

#include <string>

#include "morphology/configuration.hpp"
#include "sim/params.hpp"
#include "sim/scene.hpp"

namespace comorph::sim {

inline constexpr int kJointsPerModule = 4;     // wheel_l, wheel_r, front, back
inline constexpr int kActuatorsPerModule = 4;  // same order as below
enum ModuleActuator : int { kWheelLeft = 0, kWheelRight = 1, kFrontHinge = 2, kBackHinge = 3 };

// The whole scene with the robot `config` describes standing at the layout's start.
// All params.max_obstacles obstacle slots are written; slots beyond the layout's
// K are parked far below the floor (group 5, no contact). Throws
// std::invalid_argument naming the fault when morphology rejects `config`.
std::string build_mjcf(const Configuration& config, const RobotParams& robot, const SceneParams& scene,
                       const SceneLayout& layout);

}  // namespace comorph::sim
