// What a control step of the hierarchical trainer costs on this machine, to
// choose the quick preset's update interval, batch and network sizes
// (docs/coopt.md): env step, acting forward pass, and one motion-model update
// for several network/batch choices, each as ms and as a ratio to the env step.
#include <fmt/format.h>
#include <torch/torch.h>

#include <chrono>
#include <random>

#include "common/resources.hpp"
#include "rl/td3.hpp"
#include "task/env_config.hpp"
#include "task/multitask_env.hpp"

using namespace comorph;
using Clock = std::chrono::steady_clock;

static double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

int main() {
  rl::set_torch_threads(1, 1);
  task::EnvConfig ec = task::load_env_config(resource_path("configs/sim"));
  task::MultiTaskEnv env(ec);
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<float> u(-1, 1);
  float a[5];
  // Env steps with random actions (4 modules), resets included.
  int steps = 0;
  auto t0 = Clock::now();
  for (int ep = 0; steps < 3000; ++ep) {
    env.reset({static_cast<std::uint64_t>(ep), make_chain(4), 0, -1, sim::Variant::standard});
    for (int i = 0; i < 500 && !env.done(); ++i, ++steps) {
      for (float& x : a) x = u(rng);
      env.step(a, control::MotionMode::stair);
    }
  }
  const double env_ms = ms_since(t0) / steps;
  fmt::print("env step (4 modules, stair mode, depth {}x{}): {:.3f} ms\n", ec.robot.depth_width, ec.robot.depth_height,
             env_ms);

  struct Case { const char* name; bool image; int size; std::vector<int> hidden; int batch; };
  const Case cases[] = {
      {"state only, MLP 256x256, batch 256", false, 16, {256, 256}, 256},
      {"state only, MLP 256x256, batch 128", false, 16, {256, 256}, 128},
      {"state only, MLP 256x256x256, batch 256 (paper MLP)", false, 16, {256, 256, 256}, 256},
      {"depth 16x16 + state, paper CNN, MLP 256x256, batch 64", true, 16, {256, 256}, 64},
      {"depth 16x16 + state, paper CNN, MLP 256x256, batch 128", true, 16, {256, 256}, 128},
      {"depth 16x16 + state, paper CNN, 256x256x256, batch 256 (paper)", true, 16, {256, 256, 256}, 256},
      {"depth 8x8 + state, paper CNN, MLP 256x256, batch 128", true, 8, {256, 256}, 128},
  };
  for (const Case& c : cases) {
    rl::ObservationSpec spec;
    if (c.image) spec.image_channels = 1, spec.image_height = c.size, spec.image_width = c.size;
    spec.vector_size = task::obs::kStateSize;
    rl::Td3Config cfg;
    cfg.batch_size = c.batch;
    cfg.buffer_size = 5000;
    cfg.learning_starts = 0;
    cfg.random_action_steps = 0;
    cfg.hidden_sizes = c.hidden;
    cfg.policy_delay = 3;
    rl::Td3 td3(spec, 5, cfg, 1);
    rl::Observation o, n;
    rl::allocate(spec, o);
    rl::allocate(spec, n);
    rl::Action act;
    act.continuous.assign(5, 0.1f);
    for (int i = 0; i < 2000; ++i) {
      for (float& x : o.image) x = u(rng) * 0.5f + 0.5f;
      for (float& x : o.vector) x = u(rng);
      td3.store(o, act, 0.1f, o, false, false);
    }
    for (int i = 0; i < 3; ++i) td3.update();
    t0 = Clock::now();
    const int updates = 30;
    for (int i = 0; i < updates; ++i) td3.update();
    const double upd = ms_since(t0) / updates;
    t0 = Clock::now();
    for (int i = 0; i < 300; ++i) td3.act(o, true, act);
    const double actm = ms_since(t0) / 300;
    fmt::print("{:<66} update {:7.2f} ms ({:5.1f} env steps), act {:.3f} ms\n", c.name, upd, upd / env_ms, actm);
  }
  return 0;
}
