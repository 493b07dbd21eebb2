// Motion modes: the 5-D action in [-1, 1] -> wheel speeds and hinge targets
// (paper Eq. 4 and 5). Pure arithmetic, no MuJoCo state.
//
// Chosen reading of the paper (docs/sim.md, the motion modes):
//   a0 -> V_straight = a0 * v_straight_max                     (m/s)
//   a1 -> V_turning  = a1 * v_turn_max                         (m/s, + turns left)
//   Eq. 4, every module:  v_left  = w1 * V_straight - w2 * V_turning
//                         v_right = w1 * V_straight + w2 * V_turning
//                         wheel speed = v / wheel_radius       (rad/s)
//   a2 -> A_front = amplitude_max * (a2 + 1) / 2  (front half of the chain)
//   a4 -> A_back  = amplitude_max * (a4 + 1) / 2  (back half; 2 modules use a2 only)
//   a3 -> B       = phase_max * a3                (phase lag between neighbours, rad)
//   Eq. 5, front-plate hinge of module i = 2..N (1-based), stair mode only:
//         P_i(t) = w3 * A_i * sin(2 pi f t - w4 * B * (i - 2))   (rad)
//   Module i is in the front half when i - 2 < (N - 1) / 2 (rounded up).
//   The back-plate hinges and module 1's free front plate are held at 0; flat
//   mode holds every hinge at 0 (the chain stays straight).
#pragma once

#include <array>
#include <string>

#include "common/enum_names.hpp"
#include "morphology/configuration.hpp"  // kMaxModules

namespace comorph {
class YamlFields;
}

namespace comorph::control {

inline constexpr int kActionSize = 5;

enum class MotionMode : int { flat = 0, stair = 1 };
constexpr auto enum_names(MotionMode) {
  return std::array{EnumName{MotionMode::flat, "flat"}, EnumName{MotionMode::stair, "stair"}};
}
inline const char* mode_name(MotionMode m) { return name_at(m); }

struct ModeWeights {
  double w1;  // straight-speed weight (Eq. 4)
  double w2;  // turning weight (Eq. 4)
  double w3;  // hinge amplitude weight (Eq. 5); 0 keeps the chain straight
  double w4;  // phase-lag weight (Eq. 5)
};

struct MotionParams {
  double v_straight_max = 0.40;  // m/s, V_straight at a0 = 1
  double v_turn_max = 0.30;      // m/s, V_turning at a1 = 1
  double amplitude_max = 0.6;    // rad, hinge amplitude at a2/a4 = 1 (before w3)
  double phase_max = 3.14159265358979;  // rad, neighbour phase lag at |a3| = 1 (before w4)
  double wave_frequency = 0.6;   // Hz, f of Eq. 5
  ModeWeights flat{1.0, 0.6, 0.0, 0.0};    // fast straight, moderate turning, straight chain
  ModeWeights stair{0.5, 0.2, 1.0, 1.0};   // slow, little turning, travelling wave
  // The paper's narrow-passage mode: no scenario drives in it, but
  // configs/sim/motion.yaml sets its weights, so they are still read.
  ModeWeights narrow{0.4, 1.0, 0.0, 0.0};  // slow straight, strong turning
  const ModeWeights& weights(MotionMode m) const { return m == MotionMode::stair ? stair : flat; }
};

// Motor commands for a chain of `modules` modules (entries beyond are zero).
struct MotorCommand {
  std::array<double, kMaxModules> wheel_left{};   // rad/s
  std::array<double, kMaxModules> wheel_right{};  // rad/s
  std::array<double, kMaxModules> front_hinge{};  // rad, target of module k's front plate
  std::array<double, kMaxModules> back_hinge{};   // rad, target of module k's back plate
};

// Eq. 4 and 5 at time t (s). Action entries are clamped to [-1, 1]; wheel
// speeds are clamped to +-max_wheel_speed (rad/s).
void compute_command(const MotionParams& params, MotionMode mode, const float* action, double t,
                     int modules, double wheel_radius, double max_wheel_speed, MotorCommand& out);

// Writes a command into a MuJoCo ctrl vector laid out as in sim/mjcf.hpp
// (4 values per module: wheel_l, wheel_r, front hinge, back hinge).
void command_to_ctrl(const MotorCommand& cmd, int modules, double* ctrl);

// Every field of MotionParams with its range and meaning, modes as nested
// maps (flat: {w1: 1.0, ...}).
void add_fields(YamlFields& f, MotionParams& p);
// YAML: those fields.
// Unknown fields and out-of-range values throw naming the file and the field.
MotionParams motion_params_from_yaml(const std::string& text, const std::string& source_name,
                                     MotionParams defaults = {});

}  // namespace comorph::control
