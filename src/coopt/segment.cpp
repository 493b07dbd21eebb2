#include "coopt/segment.hpp"

#include <stdexcept>

namespace comorph::coopt {
namespace {

using MaskTable = std::array<std::array<std::uint8_t, kCandidates>, kCandidates>;

// table[c][d] = 1 when candidate d is candidate c or one c can shed modules to.
const MaskTable& mask_table() {
  static const MaskTable table = [] {
    MaskTable t{};
    for (int c = 0; c < kCandidates; ++c)
      for (int d = 0; d < kCandidates; ++d)
        t[c][d] = c == d || validate_sub_configuration(candidates()[c], candidates()[d]).empty();
    return t;
  }();
  return table;
}

}  // namespace

const std::array<Configuration, kCandidates>& candidates() {
  static const std::array<Configuration, kCandidates> chains = [] {
    std::array<Configuration, kCandidates> c;
    for (int a = 0; a < kCandidates; ++a) c[a] = make_chain(modules_of(a));
    return c;
  }();
  return chains;
}

int candidate_index(const Configuration& config) {
  for (int c = 0; c < kCandidates; ++c)
    if (candidates()[c] == config) return c;
  throw std::invalid_argument("the configuration (" + describe(config) + ") is not a candidate of the configuration model");
}

void candidate_mask(const Configuration& current, std::vector<std::uint8_t>& mask) {
  const auto& row = mask_table()[candidate_index(current)];
  mask.assign(row.begin(), row.end());
}

std::vector<std::uint8_t> candidate_mask(const Configuration& current) {
  std::vector<std::uint8_t> mask;
  candidate_mask(current, mask);
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

void to_decision_returns(std::vector<float>& r2, double gamma) {
  double later = 0;
  for (std::size_t i = r2.size(); i-- > 0;) {
    later = r2[i] + gamma * later;
    r2[i] = static_cast<float>(later);
  }
}

}  // namespace comorph::coopt
