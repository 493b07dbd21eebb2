// The configuration model's semi-MDP bookkeeping (paper Algorithm 1), torch-free:
// - the candidates: the configurations the DQN chooses among, one per action;
// - candidate masks: a candidate is valid when it is the current configuration
//   or one the robot can shed modules to (at the episode start the current
//   configuration is the longest chain, so every candidate is valid);
// - the segment a decision governs: its summed R1, its length k in control
//   steps, whether it started before the stairs were climbed, whether the r_s
//   event happened in it, and the stair energy E_c spent during it -> R2 (Eq. 7).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "coopt/config.hpp"
#include "morphology/configuration.hpp"
#include "task/rewards.hpp"

namespace comorph::coopt {

// The candidates, by action index: action a is the chain of a + kMinModules
// modules (index 0 = 2 modules ... 8 = 10 modules).
inline constexpr int kCandidates = kMaxModules - kMinModules + 1;  // 9 Q values
const std::array<Configuration, kCandidates>& candidates();
inline int modules_of(int candidate) { return candidate + kMinModules; }
inline int candidate_of(int modules) { return modules - kMinModules; }

// The action index of a candidate; throws std::invalid_argument for another configuration.
int candidate_index(const Configuration& config);

// Valid-action mask over the candidates: 1 for `current` (a candidate) and for
// each candidate morphology accepts as a sub-configuration of it.
std::vector<std::uint8_t> candidate_mask(const Configuration& current);
void candidate_mask(const Configuration& current, std::vector<std::uint8_t>& mask);  // no allocation once sized

// One configuration decision's segment.
class Segment {
 public:
  // The decision is made now: stairs_climbed = the r_s event already happened
  // in this episode; stair_energy_J = the env's E_c counter so far.
  void begin(bool stairs_climbed, double stair_energy_J);
  // After each control step: its R1 and whether the r_s event happened in it.
  void add_step(double r1, bool stairs_climbed_now);
  // R2 (Eq. 7) of the segment so far; stair_energy_J = the env's E_c counter now.
  double r2(const task::R2Params& params, double stair_height_m, double stair_energy_J) const;

  int steps() const { return steps_; }           // k of the semi-MDP transition (control steps)
  double sum_r1() const { return sum_r1_; }      // summed R1 of the segment
  bool stairs_segment() const { return stairs_segment_; }  // began before the stairs were climbed
  bool climbed() const { return climbed_; }      // r_s earned in this segment

 private:
  int steps_ = 0;
  double sum_r1_ = 0;
  bool stairs_segment_ = false;
  bool climbed_ = false;
  double energy_at_start_J_ = 0;
};

// trainer.config_target: return. In place: each decision's R2 becomes the
// R2 of its segment plus, discounted by gamma once per decision, the return
// of the decisions after it in the episode.
void to_decision_returns(std::vector<float>& r2, double gamma);

}  // namespace comorph::coopt
