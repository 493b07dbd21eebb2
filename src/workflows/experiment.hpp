// The paper's tables as runs: every column of Table I or II of
// configs/reference/paper-tables.yaml trained and evaluated as its own run
// directory under `out`, then the combined table beside the paper's and a
// full report (what `comorph experiment` does).
//
// Resumable by calling it again: a finished column is skipped, an interrupted
// one resumes from its checkpoint, an evaluation whose eval-<scenario>.json
// exists is not run again. Both tables may share one `out`: the hierarchical
// TD3 run is the same column in both.
#pragma once

#include <string>
#include <vector>

namespace comorph::workflows {

// Options of one experiment (`comorph experiment`).
struct ExperimentOptions {
  int table = 0;
  std::string config;
  std::vector<std::string> sets;
  std::string out;
  std::string only;        // run just this column ("" = all)
  int eval_episodes = 0;   // 0 = eval.episodes of the config
  int eval_seed = -1;      // first evaluation seed; -1 = eval.seed of the config
};

// Trains and evaluates the table's columns (or only `only`), writes
// out/table-N.md and out/report/; true when done. False when a training was
// interrupted (SIGINT/SIGTERM: its checkpoint is written, calling again
// continues). Throws naming the table, column, key or file on bad input,
// before anything trains.
bool run_experiment(const ExperimentOptions& options);

}  // namespace comorph::workflows
