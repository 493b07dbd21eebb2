#include "task/rewards.hpp"

namespace comorph::task {

double r2_reward(const R2Params& p, double sum_r1, bool stairs_segment, bool stairs_climbed,
                 double stair_height_m, double stair_energy_J) {
  if (!stairs_segment) return p.sigma1 * sum_r1;
  const double sigma2 = 1.0 + stair_height_m / p.s_base;
  const double r_s = stairs_climbed ? p.r_s : 0.0;
  const double r_c = (p.energy_if_climbed && !stairs_climbed) ? 0.0 : -stair_energy_J;
  return p.sigma1 * sum_r1 + sigma2 * r_s + p.sigma3 * r_c;
}

double objective(const ObjectiveWeights& w, double time_s, double energy_J, double distance_fraction) {
  return -w.w_t * time_s / w.t_max_s - w.w_e * energy_J / w.energy_scale_J + w.w_d * distance_fraction;
}

}  // namespace comorph::task
