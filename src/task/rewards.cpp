#include "task/rewards.hpp"

namespace comorph::task {

double r2_reward(const R2Params& p, double sum_r1, bool stairs_segment, bool stairs_climbed,
                 double stair_height_m, double stair_energy_J) {
  if (!stairs_segment) return p.sigma1 * sum_r1;
  const double sigma2 = 1.0 + stair_height_m / p.s_base;
  const double r_s = stairs_climbed ? p.r_s : 0.0;
  const double r_c = -stair_energy_J;
  return p.sigma1 * sum_r1 + sigma2 * r_s + p.sigma3 * r_c;
}

double objective(const ObjectiveWeights& w, double T, double E, double D) {
  return -w.w_t * T - w.w_e * E + w.w_d * D;
}

}  // namespace comorph::task
