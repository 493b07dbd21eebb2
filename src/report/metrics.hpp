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
#include "task/rewards.hpp"

namespace comorph::report {

// F(H) of one episode: task::objective (Eq. 1, the project's one definition,
// with its weights and scales documented in task/rewards.hpp) of the record's
// time, energy and distance fraction.
double objective_F(const EpisodeRecord& episode, const task::ObjectiveWeights& weights);

// Summary key of a stair height: metres, the shortest text that reads back
// as the same number ("0.06", "0.1").
std::string stair_key(double stair_height_m);

// What an evaluation measured over its episodes (the eval-<scenario>.json).
struct EvalSummary {
  int episodes = 0;  // episodes summarised
  // Success fraction (0..1) per stair-height key: every height summarize()
  // was given (NaN when no episode had it) and any other height seen; "avg" =
  // mean of the per-height fractions of the heights that had episodes (the
  // paper's "Success avg").
  std::map<std::string, double> success_rate;
  double time_s = 0;    // mean time of the SUCCESSFUL episodes, seconds; NaN when none succeeded
  double energy_J = 0;  // mean energy of the SUCCESSFUL episodes, joules; NaN when none succeeded
  double F = 0;         // mean F(H) over all episodes (dimensionless); NaN when there are none
  // Per stair-height key: configuration sequence ("4->2") -> episodes.
  std::map<std::string, std::map<std::string, int>> configurations;
  std::map<std::string, int> terminations;  // termination reason -> episodes
  // The configuration model's choice: per stair-height key, the mean modules of
  // the first configuration (NaN when no episode had that height); and the
  // share of the episodes that climbed the stairs whose last configuration has
  // 2 or 3 modules (shed after the stairs; NaN when none climbed them).
  std::map<std::string, double> first_modules;
  double shed_after_stairs = 0;
};

// `stair_heights`: the heights the episodes were drawn from (the run's
// env.scene), each reported even when no episode had it.
EvalSummary summarize(const std::vector<EpisodeRecord>& records, const task::ObjectiveWeights& weights = {},
                      const std::vector<double>& stair_heights = {});
// The stair-height keys of a summary's success_rate, lowest height first.
std::vector<std::string> stair_keys(const EvalSummary& summary);

// JSON with exactly the keys success_rate, time_s, energy_J, F, configurations,
// terminations, episodes, first_modules, shed_after_stairs; NaN is written as
// null. Reading accepts JSON without the last two (written before they existed).
nlohmann::json to_json(const EvalSummary& metrics);
// Reads that JSON back (other keys are ignored); throws naming `source` and
// the key when a key is missing or has the wrong type.
EvalSummary metrics_from_json(const nlohmann::json& json, const std::string& source);

void write_metrics_json(const std::string& path, const EvalSummary& metrics);
EvalSummary read_metrics_json(const std::string& path);

}  // namespace comorph::report
