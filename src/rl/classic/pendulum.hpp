// Pendulum-v1 exactly as Gymnasium defines it
// (gymnasium/envs/classic_control/pendulum.py, registered with
// max_episode_steps=200): swing a pole up and hold it upright.
//
// State (theta [rad], theta_dot [rad/s]); theta = 0 is upright.
// Observation [cos(theta), sin(theta), theta_dot].
// Action: torque in [-2, 2] N m; the Env takes it normalised to [-1, 1].
// Reward: -(angle_normalize(theta)^2 + 0.1 theta_dot^2 + 0.001 u^2), in [-16.27, 0].
// Never terminates; truncated after 200 steps.
#pragma once

#include "rl/classic/classic_env.hpp"

namespace comorph::rl {

struct PendulumParams {
  double max_speed = 8.0;    // rad/s, |theta_dot| clip
  double max_torque = 2.0;   // N m, |u| clip
  double dt = 0.05;          // s, one step
  double g = 10.0;           // m/s^2 (Gymnasium's default g)
  double m = 1.0;            // kg
  double l = 1.0;            // m
  int max_episode_steps = 200;
};

struct PendulumState {
  double theta = 0.0;      // rad
  double theta_dot = 0.0;  // rad/s
};

// One step of the Gymnasium dynamics with torque `u` (N m, clipped to
// +-max_torque); returns the reward of the step and advances `state`.
double pendulum_step(const PendulumParams& params, double u, PendulumState& state);

// Wraps an angle to [-pi, pi), as Gymnasium's angle_normalize.
double angle_normalize(double x);

class PendulumEnv final : public ClassicEnv<PendulumParams, PendulumState> {
 public:
  explicit PendulumEnv(PendulumParams params = {});
};

}  // namespace comorph::rl
