// Motion modes (Eq. 4, 5), R2 (Eq. 7) and F(H) (Eq. 1) numbers.
#include <gtest/gtest.h>

#include <cmath>

#include "control/motion_modes.hpp"
#include "task/env_config.hpp"
#include "task/rewards.hpp"

using namespace comorph;
using control::MotionMode;

TEST(MotionModes, Eq4WheelSpeedsPerMode) {
  const control::MotionParams p;
  const double r = 0.06, cap = 100.0;
  control::MotorCommand c;
  const float forward[5] = {1.0f, 0.0f, 0.0f, 0.0f, 0.0f};
  control::compute_command(p, MotionMode::flat, forward, 0.0, 4, r, cap, c);
  for (int k = 0; k < 4; ++k) {
    EXPECT_DOUBLE_EQ(c.wheel_left[k], p.flat.w1 * p.v_straight_max / r);
    EXPECT_DOUBLE_EQ(c.wheel_right[k], p.flat.w1 * p.v_straight_max / r);
  }
  EXPECT_EQ(c.wheel_left[4], 0.0);  // beyond the chain
  const float mixed[5] = {0.5f, -0.5f, 0.0f, 0.0f, 0.0f};
  for (MotionMode m : {MotionMode::flat, MotionMode::stair}) {
    const control::ModeWeights& w = p.weights(m);
    control::compute_command(p, m, mixed, 0.0, 3, r, cap, c);
    EXPECT_NEAR(c.wheel_left[0], (w.w1 * 0.5 * p.v_straight_max + w.w2 * 0.5 * p.v_turn_max) / r, 1e-12);
    EXPECT_NEAR(c.wheel_right[0], (w.w1 * 0.5 * p.v_straight_max - w.w2 * 0.5 * p.v_turn_max) / r, 1e-12);
  }
  // Stair mode is slower straight and turns less than flat mode; narrow turns more.
  EXPECT_LT(p.stair.w1, p.flat.w1);
  EXPECT_LT(p.stair.w2, p.flat.w2);
  EXPECT_LT(p.narrow.w1, p.flat.w1);
  EXPECT_GT(p.narrow.w2, p.flat.w2);
  // Clamping of actions and wheel speeds.
  const float big[5] = {5.0f, 0.0f, 0.0f, 0.0f, 0.0f};
  control::compute_command(p, MotionMode::flat, big, 0.0, 2, r, 3.0, c);
  EXPECT_DOUBLE_EQ(c.wheel_left[0], 3.0);
}

TEST(MotionModes, Eq5TravellingWaveOnTheFrontHinges) {
  const control::MotionParams p;
  control::MotorCommand c;
  const float a[5] = {0.0f, 0.0f, 0.5f, 0.25f, -0.5f};  // A_front = 0.75 A_max, A_back = 0.25 A_max
  const double t = 0.37;
  const int n = 6;
  control::compute_command(p, MotionMode::stair, a, t, n, 0.06, 100, c);
  const double wt = 2 * M_PI * p.wave_frequency * t, lag = p.phase_max * 0.25;
  EXPECT_EQ(c.front_hinge[0], 0.0);  // module 1's free plate
  for (int k = 1; k < n; ++k) {
    const int j = k - 1;
    const double amp = p.amplitude_max * (j < n / 2 ? 0.75 : 0.25);
    EXPECT_NEAR(c.front_hinge[k], p.stair.w3 * amp * std::sin(wt - p.stair.w4 * lag * j), 1e-12) << k;
    EXPECT_EQ(c.back_hinge[k], 0.0);
  }
  // Two modules use a2 only.
  control::compute_command(p, MotionMode::stair, a, t, 2, 0.06, 100, c);
  EXPECT_NEAR(c.front_hinge[1], p.stair.w3 * p.amplitude_max * 0.75 * std::sin(wt), 1e-12);
  // Flat mode keeps the chain straight; a2 = a4 = -1 means no wave.
  control::compute_command(p, MotionMode::flat, a, t, n, 0.06, 100, c);
  for (int k = 0; k < n; ++k) EXPECT_EQ(c.front_hinge[k], 0.0);
  const float still[5] = {1.0f, 0.0f, -1.0f, 0.3f, -1.0f};
  control::compute_command(p, MotionMode::stair, still, t, n, 0.06, 100, c);
  for (int k = 0; k < n; ++k) EXPECT_EQ(c.front_hinge[k], 0.0);
}

TEST(MotionModes, CtrlLayoutAndNames) {
  control::MotorCommand c;
  c.wheel_left[1] = 1;
  c.wheel_right[1] = 2;
  c.front_hinge[1] = 3;
  c.back_hinge[1] = 4;
  double ctrl[8] = {};
  control::command_to_ctrl(c, 2, ctrl);
  EXPECT_EQ(ctrl[4], 1);
  EXPECT_EQ(ctrl[5], 2);
  EXPECT_EQ(ctrl[6], 3);
  EXPECT_EQ(ctrl[7], 4);
  EXPECT_STREQ(control::mode_name(MotionMode::stair), "stair");
  MotionMode mode = MotionMode::flat;
  EXPECT_TRUE(enum_from_name("stair", mode));
  EXPECT_EQ(mode, MotionMode::stair);
  EXPECT_FALSE(enum_from_name("swim", mode));
  EXPECT_THROW(control::motion_params_from_yaml("stair:\n  w9: 1\n", "motion.yaml"), std::runtime_error);
  EXPECT_EQ(control::motion_params_from_yaml("stair:\n  w1: 0.3\n", "motion.yaml").stair.w1, 0.3);
}

TEST(Rewards, R2AndObjective) {
  const task::R2Params p;
  // Stairs segment, 0.08 m climbed, 1000 J: 50 + (1 + 2) * 60 - 0.003 * 1000.
  EXPECT_NEAR(task::r2_reward(p, 50.0, true, true, 0.08, 1000.0), 50.0 + 3.0 * 60.0 - 3.0, 1e-12);
  EXPECT_NEAR(task::r2_reward(p, 50.0, true, false, 0.08, 1000.0), 50.0 - 3.0, 1e-12);
  EXPECT_NEAR(task::r2_reward(p, 50.0, false, true, 0.08, 1000.0), 50.0, 1e-12);  // after the stairs
  task::R2Params on_climb = p;
  on_climb.energy_if_climbed = true;  // a failed climb pays no energy, a climb pays as before
  EXPECT_NEAR(task::r2_reward(on_climb, 50.0, true, false, 0.08, 1000.0), 50.0, 1e-12);
  EXPECT_NEAR(task::r2_reward(on_climb, 50.0, true, true, 0.08, 1000.0), 50.0 + 3.0 * 60.0 - 3.0, 1e-12);
  const task::ObjectiveWeights w{2.0, 3.0, 4.0, 120.0, 20000.0};
  // T = 60 s / 120 s = 0.5, E = 2000 J / 20000 J = 0.1, D = 0.9.
  EXPECT_NEAR(task::objective(w, 60.0, 2000.0, 0.9), -1.0 - 0.3 + 3.6, 1e-12);
}

TEST(Config, TaskYamlErrorsNameTheField) {
  try {
    task::task_params_from_yaml("r1:\n  tau9: 3\n", "task.yaml");
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("task.yaml: field 'r1.tau9'"), std::string::npos) << e.what();
  }
  EXPECT_EQ(task::task_params_from_yaml("r1:\n  tau1: 50\nmax_steps: 100\n", "t").r1.tau1, 50.0);
  const task::EnvConfig c = task::load_env_config(std::string(COMORPH_SOURCE_DIR) + "/configs/sim");
  EXPECT_EQ(c.task.max_steps, 3500);
  EXPECT_EQ(c.motion.stair.w1, control::MotionParams{}.stair.w1);
}
