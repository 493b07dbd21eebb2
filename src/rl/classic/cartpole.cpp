#include "rl/classic/cartpole.hpp"

#include <cmath>
#include <stdexcept>

namespace comorph::rl {

bool cartpole_step(const CartPoleParams& p, int action, CartPoleState& s) {
  double x = s[0], x_dot = s[1], theta = s[2], theta_dot = s[3];
  const double total_mass = p.masspole + p.masscart;
  const double polemass_length = p.masspole * p.length;
  const double force = action == 1 ? p.force_mag : -p.force_mag;
  const double costheta = std::cos(theta), sintheta = std::sin(theta);
  const double temp = (force + polemass_length * theta_dot * theta_dot * sintheta) / total_mass;
  const double thetaacc = (p.gravity * sintheta - costheta * temp) /
                          (p.length * (4.0 / 3.0 - p.masspole * costheta * costheta / total_mass));
  const double xacc = temp - polemass_length * thetaacc * costheta / total_mass;
  // Gymnasium's default kinematics_integrator "euler".
  x = x + p.tau * x_dot;
  x_dot = x_dot + p.tau * xacc;
  theta = theta + p.tau * theta_dot;
  theta_dot = theta_dot + p.tau * thetaacc;
  s = {x, x_dot, theta, theta_dot};
  return x < -p.x_threshold || x > p.x_threshold || theta < -p.theta_threshold ||
         theta > p.theta_threshold;
}

namespace {

CartPoleState initial_state(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  CartPoleState s;
  for (double& v : s) v = u(rng);
  return s;
}

StepResult advance(const CartPoleParams& p, const Action& action, CartPoleState& s) {
  if (action.discrete != 0 && action.discrete != 1)
    throw std::invalid_argument("CartPoleEnv::step: action must be 0 or 1, got " +
                                std::to_string(action.discrete));
  StepResult r;
  r.terminated = cartpole_step(p, action.discrete, s);
  r.reward = 1.0f;  // also on the terminating step, as Gymnasium
  return r;
}

void observe(const CartPoleState& s, Observation& o) {
  o.image.clear();
  o.vector.resize(4);
  for (int i = 0; i < 4; ++i) o.vector[i] = static_cast<float>(s[i]);
  o.valid_actions.assign(2, 1);  // both actions always valid
}

}  // namespace

CartPoleEnv::CartPoleEnv(CartPoleParams params)
    : ClassicEnv({"CartPole-v1", {0, 0, 0, 4}, {ActionKind::kDiscrete, 2}, initial_state, advance, observe},
                 params) {}

}  // namespace comorph::rl
