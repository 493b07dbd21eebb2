// bench_sim: cost of one environment control step (32 ms, 16 physics steps,
// depth image, distance sensors, termination, reward) for 2, 6 and 10 modules,
// in steps per second and as a ratio to the raw mj_step cost of the same
// physics (16 x mj_step on a copy of the same model and state).
// Goal (docs/sim.md): >= 1000 control steps/s for 6 modules, overhead <= 25 %.
#include <fmt/format.h>

#include <time.h>

#include <algorithm>
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
  fmt::print("{:>7} {:>14} {:>14} {:>14} {:>14} {:>10} {:>12} {:>16} {:>8}\n", "modules", "env steps/s",
             "env us/step", "raw us/step", "depth us/img", "env/raw", "overhead %", "wall steps/s", "replay");
  for (int n : {2, 6, 10}) {
    task::MultiTaskEnv env(config);
    task::EpisodeSpec spec;
    spec.seed = 1;
    spec.configuration = make_chain(n);
    spec.stair_height = 0.06;
    // A stair-mode wave up the stairs: contacts with steps, hinges moving.
    const float action[5] = {0.8f, 0.0f, 0.5f, -0.5f, 0.5f};
    env.reset(spec);
    // The env run records its ctrl and episode starts so that the raw run
    // replays exactly the same physics (same states, contacts, solver work).
    const int nu = env.world().model()->nu;
    std::vector<double> ctrl_log(std::size_t(steps) * nu);
    std::vector<char> reset_before(steps, 0);
    const double w0 = wall_now();
    const auto t0 = Clock::now();
    for (int i = 0; i < steps; ++i) {
      if (env.done()) {
        env.reset(spec);
        reset_before[i] = 1;
      }
      env.step(action, control::MotionMode::stair);
      std::copy(env.world().data()->ctrl, env.world().data()->ctrl + nu, ctrl_log.begin() + std::size_t(i) * nu);
    }
    const double env_s = seconds_since(t0);
    const double env_wall_s = wall_now() - w0;
    const std::vector<double> env_final(env.world().data()->qpos, env.world().data()->qpos + env.world().model()->nq);

    // Raw physics: 16 x mj_step per control step on a copy of the model and the
    // episode's start state, with the recorded ctrl.
    env.reset(spec);
    const mjModel* m = env.world().model();
    mjData* start = mj_makeData(m);
    mjData* d = mj_makeData(m);
    mj_copyData(start, m, env.world().data());
    mj_copyData(d, m, start);
    const int substeps = env.world().substeps();
    const auto t1 = Clock::now();
    for (int i = 0; i < steps; ++i) {
      if (reset_before[i]) mj_copyData(d, m, start);
      std::copy(ctrl_log.begin() + std::size_t(i) * nu, ctrl_log.begin() + std::size_t(i + 1) * nu, d->ctrl);
      for (int s = 0; s < substeps; ++s) mj_step(m, d);
    }
    const double raw_s = seconds_since(t1);
    // Untimed check that the replay is the env's physics: with the env's one
    // mj_kinematics per control step (it renormalises the root quaternion in
    // qpos, which changes the last bits) the end state is bit-identical.
    mj_copyData(d, m, start);
    for (int i = 0; i < steps; ++i) {
      if (reset_before[i]) mj_copyData(d, m, start);
      std::copy(ctrl_log.begin() + std::size_t(i) * nu, ctrl_log.begin() + std::size_t(i + 1) * nu, d->ctrl);
      for (int s = 0; s < substeps; ++s) mj_step(m, d);
      mj_kinematics(m, d);
    }
    const bool same = std::equal(env_final.begin(), env_final.end(), d->qpos);
    mj_deleteData(d);
    mj_deleteData(start);

    // Depth image alone.
    std::vector<float> depth(config.robot.depth_width * config.robot.depth_height);
    const auto t2 = Clock::now();
    const int images = 2000;
    for (int i = 0; i < images; ++i) env.world().render_depth(depth.data());
    const double depth_s = seconds_since(t2);

    const double env_us = 1e6 * env_s / steps, raw_us = 1e6 * raw_s / steps;
    fmt::print("{:>7} {:>14.0f} {:>14.1f} {:>14.1f} {:>14.1f} {:>10.3f} {:>12.1f} {:>16.0f} {:>8}\n", n,
               steps / env_s, env_us, raw_us, 1e6 * depth_s / images, env_us / raw_us,
               100.0 * (env_us / raw_us - 1.0), steps / env_wall_s, same ? "same" : "DIFFERS");
  }
  fmt::print("times are thread CPU time (cost per core); wall steps/s includes waiting for a shared core\n");
  fmt::print("replay: the raw run replays the env's ctrl from the same start states (same = bit-identical end state, checked untimed)\n");
  fmt::print("env/raw: env step time over 16 x mj_step of the same chain (1.25 = the 25 % goal)\n");
  return 0;
}
