// CartPole-v1 exactly as Gymnasium defines it
// (gymnasium/envs/classic_control/cartpole.py, registered with
// max_episode_steps=500, reward_threshold=475): balance a pole on a cart.
//
// State (x [m], x_dot [m/s], theta [rad], theta_dot [rad/s]), explicit Euler.
// Actions: 0 pushes left, 1 pushes right (force 10 N).
// Reward 1 for every step, including the terminating one.
// Terminated when |x| > 2.4 m or |theta| > 12 deg; truncated after 500 steps.
#pragma once

#include <array>

#include "rl/classic/classic_env.hpp"

namespace comorph::rl {

struct CartPoleParams {
  double gravity = 9.8;      // m/s^2
  double masscart = 1.0;     // kg
  double masspole = 0.1;     // kg
  double length = 0.5;       // m, half the pole's length
  double force_mag = 10.0;   // N
  double tau = 0.02;         // s, one step
  double theta_threshold = 12.0 * 2.0 * M_PI / 360.0;  // rad
  double x_threshold = 2.4;  // m
  int max_episode_steps = 500;
};

using CartPoleState = std::array<double, 4>;  // x, x_dot, theta, theta_dot

// One Euler step with action 0 (left) or 1 (right); returns true when the new
// state is terminal.
bool cartpole_step(const CartPoleParams& params, int action, CartPoleState& state);

class CartPoleEnv final : public ClassicEnv<CartPoleParams, CartPoleState> {
 public:
  explicit CartPoleEnv(CartPoleParams params = {});
};

}  // namespace comorph::rl
