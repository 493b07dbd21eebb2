// Everything an episode of the multi-task scenario depends on, in one struct
// with documented defaults (units on every field), loadable from configs/sim/.
#pragma once

#include <string>

#include "control/motion_modes.hpp"
#include "sim/params.hpp"
#include "task/rewards.hpp"

namespace comorph {
class YamlFields;
}

namespace comorph::task {

struct TaskParams {
  R1Params r1;                 // Eq. 6
  R2Params r2;                 // Eq. 7
  ObjectiveWeights objective;  // Eq. 1
  int max_steps = 3500;        // control steps before truncation (~112 s at 32 ms)
  double overturn_up_z = 0.2;  // a module whose up axis has a world z below this is overturned (~78 deg tilt)
  double start_zone_length = 3.0;  // m behind the start face the robot may back up before leaving the area
  double stair_goal_offset = 0.3;  // m: goal while the stairs are not climbed = top edge + this + chain length
};

struct EnvConfig {
  sim::RobotParams robot;
  sim::SceneParams scene;
  control::MotionParams motion;
  TaskParams task;
};

// Loads <dir>/robot.yaml, scene.yaml, motion.yaml and task.yaml (each optional:
// a missing file keeps the defaults). Errors name the file and the field; a
// `dir` that is not a directory is an error (not the built-in defaults).
EnvConfig load_env_config(const std::string& dir);
// What of <dir> a run depends on, as text: per file its name and its YAML
// parsed and emitted again (comments and layout do not count, values do; an
// absent file says so). Part of a run's identity: a resume compares it, so an
// edited robot.yaml cannot change a run's physics halfway.
std::string env_files_text(const std::string& dir);
// Every field of TaskParams with its range and meaning.
void add_fields(YamlFields& f, TaskParams& p);
TaskParams task_params_from_yaml(const std::string& text, const std::string& source_name,
                                 TaskParams defaults = {});

}  // namespace comorph::task
