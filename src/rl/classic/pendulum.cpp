#include "rl/classic/pendulum.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace comorph::rl {

double angle_normalize(double x) {
  // Python's % is a floored modulo: ((x + pi) % (2 pi)) - pi.
  const double two_pi = 2.0 * M_PI;
  double r = std::fmod(x + M_PI, two_pi);
  if (r < 0) r += two_pi;
  return r - M_PI;
}

double pendulum_step(const PendulumParams& p, double u, PendulumState& s) {
  u = std::clamp(u, -p.max_torque, p.max_torque);
  const double th = s.theta, thdot = s.theta_dot;
  const double an = angle_normalize(th);
  const double cost = an * an + 0.1 * thdot * thdot + 0.001 * u * u;
  double new_thdot = thdot + (3.0 * p.g / (2.0 * p.l) * std::sin(th) + 3.0 / (p.m * p.l * p.l) * u) * p.dt;
  new_thdot = std::clamp(new_thdot, -p.max_speed, p.max_speed);
  s.theta = th + new_thdot * p.dt;  // semi-implicit Euler, as Gymnasium
  s.theta_dot = new_thdot;
  return -cost;
}

namespace {

PendulumState initial_state(std::mt19937_64& rng) {
  // Gymnasium: uniform(low=-[pi, 1], high=[pi, 1]).
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), speed(-1.0, 1.0);
  PendulumState s;
  s.theta = angle(rng);
  s.theta_dot = speed(rng);
  return s;
}

StepResult advance(const PendulumParams& p, const Action& action, PendulumState& s) {
  if (action.continuous.size() != 1)
    throw std::invalid_argument("PendulumEnv::step: expected 1 continuous action, got " +
                                std::to_string(action.continuous.size()));
  const double u = static_cast<double>(action.continuous[0]) * p.max_torque;
  StepResult r;
  r.reward = static_cast<float>(pendulum_step(p, u, s));
  r.terminated = false;  // never: only the time limit ends an episode
  return r;
}

void observe(const PendulumState& s, Observation& o) {
  o.image.clear();
  o.valid_actions.clear();
  o.vector.resize(3);
  o.vector[0] = static_cast<float>(std::cos(s.theta));
  o.vector[1] = static_cast<float>(std::sin(s.theta));
  o.vector[2] = static_cast<float>(s.theta_dot);
}

}  // namespace

PendulumEnv::PendulumEnv(PendulumParams params)
    : ClassicEnv({"Pendulum-v1", {0, 0, 0, 3}, {ActionKind::kContinuous, 1}, initial_state, advance, observe},
                 params) {}

}  // namespace comorph::rl
