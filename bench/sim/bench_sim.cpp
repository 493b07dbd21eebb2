// bench_sim: cost of one environment control step (32 ms, 16 physics steps,
// depth image, distance sensors, termination, reward) for 2, 6 and 10 modules,
// in steps per second and as a ratio to the raw mj_step cost of the same
// physics (16 x mj_step on a copy of the same model and state).
// Goal (issue 2): >= 1000 control steps/s for 6 modules, overhead <= 25 %.
#include <fmt/format.h>

#include <chrono>
#include <cstdlib>
#include <vector>

#include "task/multitask_env.hpp"

using namespace comorph;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  const int steps = argc > 1 ? std::atoi(argv[1]) : 3000;  // control steps per measurement
  const task::EnvConfig config;
  fmt::print("bench_sim: {} control steps per case, depth {}x{}, {} physics steps of {:.3f} s per control step\n",
             steps, config.robot.depth_width, config.robot.depth_height,
             int(config.robot.control_period / config.robot.physics_timestep + 0.5), config.robot.physics_timestep);
  fmt::print("{:>7} {:>14} {:>14} {:>14} {:>14} {:>10} {:>12}\n", "modules", "env steps/s", "env us/step",
             "raw us/step", "depth us/img", "env/raw", "overhead %");
  for (int n : {2, 6, 10}) {
    task::MultiTaskEnv env(config);
    task::EpisodeSpec spec;
    spec.seed = 1;
    spec.modules = n;
    spec.stair_height = 0.06;
    // A stair-mode wave up the stairs: contacts with steps, hinges moving.
    const float action[5] = {0.8f, 0.0f, 0.5f, -0.5f, 0.5f};
    env.reset(spec);
    // Record the trajectory's start states so that the raw run replays the same physics.
    std::vector<double> ctrl;
    int done_resets = 0;
    const auto t0 = Clock::now();
    for (int i = 0; i < steps; ++i) {
      if (env.done()) {
        env.reset(spec);
        ++done_resets;
      }
      env.step(action, control::MotionMode::stair);
    }
    const double env_s = seconds_since(t0);

    // Raw physics: the same model and start state, 16 mj_step per control step, ctrl
    // from the same motion mode (computing ctrl is part of the env's overhead).
    env.reset(spec);
    const mjModel* m = env.world().model();
    mjData* d = mj_makeData(m);
    mj_copyData(d, m, env.world().data());
    control::MotorCommand cmd;
    const int substeps = env.world().substeps();
    std::vector<double> c(m->nu);
    control::compute_command(config.motion, control::MotionMode::stair, action, 0.0, n, config.robot.wheel_radius,
                             config.robot.wheel_max_speed, cmd);
    control::command_to_ctrl(cmd, n, c.data());
    std::vector<double> qpos0(d->qpos, d->qpos + m->nq);
    const auto t1 = Clock::now();
    for (int i = 0; i < steps; ++i) {
      if (i % 400 == 0) {  // episodes of similar length as the env's
        mj_resetData(m, d);
        std::copy(qpos0.begin(), qpos0.end(), d->qpos);
      }
      control::compute_command(config.motion, control::MotionMode::stair, action, d->time, n,
                               config.robot.wheel_radius, config.robot.wheel_max_speed, cmd);
      control::command_to_ctrl(cmd, n, d->ctrl);
      for (int s = 0; s < substeps; ++s) mj_step(m, d);
    }
    const double raw_s = seconds_since(t1);
    mj_deleteData(d);

    // Depth image alone.
    std::vector<float> depth(config.robot.depth_width * config.robot.depth_height);
    const auto t2 = Clock::now();
    const int images = 2000;
    for (int i = 0; i < images; ++i) env.world().render_depth(depth.data());
    const double depth_s = seconds_since(t2);

    const double env_us = 1e6 * env_s / steps, raw_us = 1e6 * raw_s / steps;
    fmt::print("{:>7} {:>14.0f} {:>14.1f} {:>14.1f} {:>14.1f} {:>10.3f} {:>12.1f}\n", n, steps / env_s, env_us,
               raw_us, 1e6 * depth_s / images, env_us / raw_us, 100.0 * (env_us / raw_us - 1.0));
  }
  fmt::print("env/raw: env step time over 16 x mj_step of the same chain (1.25 = the 25 % goal)\n");
  return 0;
}
