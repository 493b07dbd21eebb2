// The evaluation summary of a set of episodes: success per stair height, time
// and energy of the successful episodes, F(H) of Eq. 1, the configurations
// chosen and why episodes ended. Its JSON form is the eval-<scenario>.json of a
// run directory (docs/report.md).
#pragma once

#include <map>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "report/episode_record.hpp"

namespace comorph::report {

// Weights and scales of F(H) = -w_t T - w_e E + w_d D (paper Eq. 1), with
// T = time / t_max, E = energy / capacity, D = distance done / initial distance.
// The paper does not print its weights. Fitting its nine (Time, Battery,
// Success avg, F) columns of Tables I and II by least squares with gnuplot gives
// w_t = 0.94, w_e = 2.01, w_d = 2.01 for t_max = 112 s and E = Battery/20000 J;
// with w = (1, 2, 2) and t_max = 120 s every paper F is matched within 0.02
// (docs/report.md). So the weights default to (1, 2, 2); T and E follow
// DESIGN.md (t_max = the 3500-step cap, E per battery on board), and
// paper_fit() gives the reading that reproduces the paper's F column.
struct FWeights {
  double w_t = 1.0;                    // weight of the time term T (dimensionless)
  double w_e = 2.0;                    // weight of the energy term E (dimensionless)
  double w_d = 2.0;                    // weight of the distance term D (dimensionless)
  double t_max_s = 112.0;              // time that makes T = 1, seconds (3500 steps x 32 ms)
  double battery_capacity_J = 20000.0; // one module's battery, joules
  bool energy_per_module = true;       // E = energy / (modules_total x capacity); false: energy / capacity

  // The reading under which the paper's F values come out: t_max = 120 s,
  // E = energy / one battery's capacity.
  static FWeights paper_fit();
};

// F(H) of one episode (throws if modules_total < 1 with energy_per_module).
double objective_F(const EpisodeRecord& episode, const FWeights& weights);

// The three stair heights of the paper's protocol, as summary keys.
const std::vector<std::string>& paper_stair_keys();  // {"0.04", "0.06", "0.08"}
// Summary key of a stair height: metres with two decimals ("0.06").
std::string stair_key(double stair_height_m);

struct Metrics {
  int episodes = 0;  // episodes summarised
  // Success fraction (0..1) per stair-height key; always has "0.04", "0.06",
  // "0.08" (NaN when no episode had that height) and any other height seen;
  // "avg" = mean of the per-height fractions of the heights that had episodes
  // (the paper's "Success avg").
  std::map<std::string, double> success_rate;
  double time_s = 0;    // mean time of the SUCCESSFUL episodes, seconds; NaN when none succeeded
  double energy_J = 0;  // mean energy of the SUCCESSFUL episodes, joules; NaN when none succeeded
  double F = 0;         // mean F(H) over all episodes (dimensionless); NaN when there are none
  // Per stair-height key: configuration sequence ("4->2") -> episodes.
  std::map<std::string, std::map<std::string, int>> configurations;
  std::map<std::string, int> terminations;  // termination reason -> episodes
};

Metrics summarize(const std::vector<EpisodeRecord>& records, const FWeights& weights = {});

// JSON with exactly the keys success_rate, time_s, energy_J, F, configurations,
// terminations, episodes; NaN is written as null.
nlohmann::json to_json(const Metrics& metrics);
// Reads that JSON back (other keys are ignored); throws naming `source` and
// the key when a key is missing or has the wrong type.
Metrics metrics_from_json(const nlohmann::json& json, const std::string& source);

void write_metrics_json(const std::string& path, const Metrics& metrics);
Metrics read_metrics_json(const std::string& path);

}  // namespace comorph::report
