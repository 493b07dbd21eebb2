// Rewards and the objective of the multi-task episode (paper Eq. 1, 6, 7).
#pragma once

#include <string>

namespace comorph::task {

// R1 (Eq. 6), per control step: tau1 * dD + tau2 * cos(beta) + tau3 * r_u + tau4 * r_g,
// tau4 = 1 + alpha_g * (1 - t / t_sum) (read as a bonus for finishing early).
struct R1Params {
  double tau1 = 100.0;     // per m of progress towards the current goal
  double tau2 = 0.05;      // heading term weight
  double tau3 = 1.0;       // failure term weight
  double r_u = -10.0;      // failure reward (collision, overturn, leaving the area, empty battery, unstable)
  double r_g = 100.0;      // reward on reaching the target
  double alpha_g = 1.0;    // early-finish bonus weight in tau4
  double t_sum = 3500.0;   // control steps, normaliser of tau4
};

// R2 (Eq. 7), per configuration decision over its segment:
// sigma1 * sum(R1) + sigma2 * r_s + sigma3 * r_c with r_c = -E_c (a cost).
// On stairs: sigma1 = 1, sigma2 = 1 + s_ht / s_base, sigma3 = 0.003; after: sigma2 = sigma3 = 0.
struct R2Params {
  double sigma1 = 1.0;     // weight of the summed R1
  double s_base = 0.04;    // m, stair height normaliser of sigma2
  double r_s = 60.0;       // reward when the stairs are climbed in the segment
  double sigma3 = 0.003;   // per J of stair energy
  // The paper's r_c is "the energy consumed when passing through the stair".
  // false: every stairs segment pays for its stair energy, climbed or not;
  // true: only the segment that climbed them does (a failed climb's r_c = 0), so a
  // short failed attempt is not cheaper than a long failed one.
  bool energy_if_climbed = false;
};

// Eq. 7 for one segment. stairs_segment: the segment started before the stairs
// were climbed; stairs_climbed: r_s was earned in it; stair_energy_J: E_c, the
// joules spent on the stairs during the segment (charged per p.energy_if_climbed).
double r2_reward(const R2Params& p, double sum_r1, bool stairs_segment, bool stairs_climbed,
                 double stair_height_m, double stair_energy_J);

// F(H) (Eq. 1) = -w_t * T - w_e * E + w_d * D, with T = time / t_max,
// E = energy / energy_scale, D = distance done / initial distance.
// The paper prints neither its weights nor its scales. A least-squares fit of
// its nine (Time, Battery, Success avg, F) columns (Tables I and II) gives
// w = (0.94, 2.01, 2.01); with w = (1, 2, 2), t_max = 120 s and E per ONE
// battery (20000 J, not N batteries) every F of the paper comes out within
// 0.02 (tests/report/test_paper_reference.cpp). We take that reading, so that
// our F stands next to the paper's, and because charging the whole robot's
// energy against one battery is what makes long chains pay for their modules.
// This is the only definition of F: the env's metrics, the trainer's logs and
// the evaluation JSON all use it.
struct ObjectiveWeights {
  double w_t = 1.0;               // weight of T (dimensionless)
  double w_e = 2.0;               // weight of E (dimensionless)
  double w_d = 2.0;               // weight of D (dimensionless)
  double t_max_s = 120.0;         // s: the time that makes T = 1
  double energy_scale_J = 20000;  // J: the energy that makes E = 1 (one module's battery)
};
double objective(const ObjectiveWeights& w, double time_s, double energy_J, double distance_fraction);

}  // namespace comorph::task
