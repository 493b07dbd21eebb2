// bench_sim: cost of one environment control step (32 ms, 16 physics steps,
// depth image, distance sensors, termination, reward) for 2, 6 and 10 modules,
// in steps per second and as a ratio to the raw mj_step cost of the same
// physics (16 x mj_step on a copy of the same model and state).
// Goal (issue 2): >= 1000 control steps/s for 6 modules, overhead <= 25 %.
#include <fmt/format.h>

#include <time.h>

#include <chrono>
#include <cstdlib>
#include <vector>

#include "task/multitask_env.hpp"

using namespace comorph;
// Thread CPU time: on a shared machine (other jobs on the same cores) wall time
// counts the time this thread waits for a core; CPU time is the cost per core.
struct Clock {
  using time_point = double;
  static double now() {
    timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
  }
};

namespace {

double seconds_since(double t0) { return Clock::now() - t0; }
double wall_now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

}  // namespace

int main(int argc, char** argv) {
  const int steps = argc > 1 ? std::atoi(argv[1]) : 3000;  // control steps per measurement
  const task::EnvConfig config;
  fmt::print("bench_sim: {} control steps per case, depth {}x{}, {} physics steps of {:.3f} s per control step\n",
             steps, config.robot.depth_width, config.robot.depth_height,
             int(config.robot.control_period / config.robot.physics_timestep + 0.5), config.robot.physics_timestep);
  fmt::print("{:>7} {:>14} {:>14} {:>14} {:>14} {:>10} {:>12} {:>16}\n", "modules", "env steps/s", "env us/step",
             "raw us/step", "depth us/img", "env/raw", "overhead %", "wall steps/s");
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
    const double w0 = wall_now();
    const auto t0 = Clock::now();
    for (int i = 0; i < steps; ++i) {
      if (env.done()) {
        env.reset(spec);
        ++done_resets;
      }
      env.step(action, control::MotionMode::stair);
    }
    const double env_s = seconds_since(t0);
    const double env_wall_s = wall_now() - w0;

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
    fmt::print("{:>7} {:>14.0f} {:>14.1f} {:>14.1f} {:>14.1f} {:>10.3f} {:>12.1f} {:>16.0f}\n", n, steps / env_s,
               env_us, raw_us, 1e6 * depth_s / images, env_us / raw_us, 100.0 * (env_us / raw_us - 1.0),
               steps / env_wall_s);
  }
  fmt::print("times are thread CPU time (cost per core); wall steps/s includes waiting for a shared core\n");
  fmt::print("env/raw: env step time over 16 x mj_step of the same chain (1.25 = the 25 % goal)\n");
  return 0;
}
