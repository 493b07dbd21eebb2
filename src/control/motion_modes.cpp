#include "control/motion_modes.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/yaml_fields.hpp"

namespace comorph::control {

void compute_command(const MotionParams& p, MotionMode mode, const float* action, double t,
                     int modules, double wheel_radius, double max_wheel_speed, MotorCommand& out) {
  double a[kActionSize];
  for (int i = 0; i < kActionSize; ++i) a[i] = std::clamp(double(action[i]), -1.0, 1.0);
  const ModeWeights& w = p.weights(mode);
  const double v_straight = a[0] * p.v_straight_max;
  const double v_turn = a[1] * p.v_turn_max;
  const double left = std::clamp((w.w1 * v_straight - w.w2 * v_turn) / wheel_radius, -max_wheel_speed, max_wheel_speed);
  const double right = std::clamp((w.w1 * v_straight + w.w2 * v_turn) / wheel_radius, -max_wheel_speed, max_wheel_speed);
  const double a_front = p.amplitude_max * 0.5 * (a[2] + 1.0);
  const double a_back = modules > 2 ? p.amplitude_max * 0.5 * (a[4] + 1.0) : a_front;
  const double lag = p.phase_max * a[3];
  const double omega_t = 2.0 * M_PI * p.wave_frequency * t;
  const int front_count = (modules) / 2;  // hinges i-2 = 0..N-2; first ceil((N-1)/2) are "front"
  for (int k = 0; k < kMaxModules; ++k) {
    const bool used = k < modules;
    out.wheel_left[k] = used ? left : 0.0;
    out.wheel_right[k] = used ? right : 0.0;
    out.back_hinge[k] = 0.0;
    out.front_hinge[k] = 0.0;
    if (used && k >= 1 && w.w3 != 0.0) {
      const int j = k - 1;  // = i - 2 for 1-based module i = k + 1
      const double amplitude = j < front_count ? a_front : a_back;
      out.front_hinge[k] = w.w3 * amplitude * std::sin(omega_t - w.w4 * lag * j);
    }
  }
}

void command_to_ctrl(const MotorCommand& cmd, int modules, double* ctrl) {
  for (int k = 0; k < modules; ++k) {
    ctrl[4 * k + 0] = cmd.wheel_left[k];
    ctrl[4 * k + 1] = cmd.wheel_right[k];
    ctrl[4 * k + 2] = cmd.front_hinge[k];
    ctrl[4 * k + 3] = cmd.back_hinge[k];
  }
}

void add_fields(YamlFields& f, MotionParams& p) {
  f.add("v_straight_max", &p.v_straight_max, 0, 5, "m/s, straight speed at a0 = 1");
  f.add("v_turn_max", &p.v_turn_max, 0, 5, "m/s, turning speed at a1 = 1");
  f.add("amplitude_max", &p.amplitude_max, 0, 3, "rad, hinge wave amplitude at a2/a4 = 1 (before w3)");
  f.add("phase_max", &p.phase_max, 0, 6.3, "rad, phase lag between neighbours at |a3| = 1 (before w4)");
  f.add("wave_frequency", &p.wave_frequency, 0, 10, "Hz, f of the hinge wave (Eq. 5)");
  for (auto [name, w] : {std::pair<const char*, ModeWeights*>{"flat", &p.flat},
                         {"stair", &p.stair}, {"narrow", &p.narrow}}) {
    const std::string n = name;
    f.add(n + ".w1", &w->w1, 0, 5, n + " mode: weight of the straight speed (Eq. 4)");
    f.add(n + ".w2", &w->w2, 0, 5, n + " mode: weight of the turning speed (Eq. 4)");
    f.add(n + ".w3", &w->w3, 0, 5, n + " mode: weight of the hinge amplitude (Eq. 5); 0 keeps the chain straight");
    f.add(n + ".w4", &w->w4, 0, 5, n + " mode: weight of the phase lag (Eq. 5)");
  }
}

MotionParams motion_params_from_yaml(const std::string& text, const std::string& source,
                                     MotionParams p) {
  YamlFields f(source);
  add_fields(f, p);
  f.apply_text(text);
  return p;
}

}  // namespace comorph::control
