#include "coopt/segment.hpp"

#include <stdexcept>
#include <string>

namespace comorph::coopt {

void candidate_mask(int max_modules, std::vector<std::uint8_t>& mask) {
  if (max_modules < kMinModules || max_modules > kMaxModules)
    throw std::invalid_argument("candidate_mask: " + std::to_string(max_modules) + " modules is outside [2, 10]");
  mask.resize(kCandidates);
  for (int c = 0; c < kCandidates; ++c) mask[c] = modules_of(c) <= max_modules ? 1 : 0;
}

std::vector<std::uint8_t> candidate_mask(int max_modules) {
  std::vector<std::uint8_t> mask;
  candidate_mask(max_modules, mask);
  return mask;
}

void Segment::begin(bool stairs_climbed, double stair_energy_J) {
  steps_ = 0;
  sum_r1_ = 0;
  stairs_segment_ = !stairs_climbed;
  climbed_ = false;
  energy_at_start_J_ = stair_energy_J;
}

void Segment::add_step(double r1, bool stairs_climbed_now) {
  ++steps_;
  sum_r1_ += r1;
  climbed_ = climbed_ || stairs_climbed_now;
}

double Segment::r2(const task::R2Params& params, double stair_height_m, double stair_energy_J) const {
  return task::r2_reward(params, sum_r1_, stairs_segment_, climbed_, stair_height_m,
                         stair_energy_J - energy_at_start_J_);
}

}  // namespace comorph::coopt
