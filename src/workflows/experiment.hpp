// The paper's tables as runs: every column of Table I or II of
// configs/reference/paper-tables.yaml, for each training seed, trained and
// evaluated as its own run directory under `out`, then the combined table
// beside the paper's and a full report (what `comorph experiment` does).
//
// Resumable by calling it again: a finished run is skipped, an interrupted
// one resumes from its checkpoint, an evaluation whose eval-<scenario>.json
// exists is not run again. Both tables may share one `out`: the hierarchical
// TD3 run is the same column in both.
//
// The runs need not be trained by this process: the job list (one command
// line per column x seed) runs under GNU parallel, the Slurm array job under
// sbatch; `collect` then makes the table from what exists.
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
  // Training seeds. Empty: one run per column, out/COLUMN, with the config's
  // trainer.seed. Else one run per column and seed, out/COLUMN-seed-S.
  std::vector<int> seeds;
  int eval_episodes = 0;   // 0 = eval.episodes of the config
  int eval_seed = -1;      // first evaluation seed; -1 = eval.seed of the config
  bool no_table = false;   // train and evaluate only: the work of one job, no table
  bool collect = false;    // train nothing: the table and report from the runs that exist
  // With collect: the table from these run directories (any names, matched
  // to the columns by their run.yaml) instead of out's column runs.
  std::vector<std::string> runs;
  std::string jobs_file;   // train nothing: write one command line per run here
  std::string slurm_file;  // train nothing: write a Slurm array job, one task per run, here
};

// "1-3", "1,2,5" or "1-3,7" as seeds (ascending, each once); throws naming
// --seeds on anything else.
std::vector<int> parse_seeds(const std::string& text);

// Does what the options ask: trains and evaluates the runs (or only
// `only`'s), writes out/table-N.md and out/report/; or with collect only
// the table and report; or with jobs_file / slurm_file only those files.
// True when done. False when a training was interrupted (SIGINT/SIGTERM:
// its checkpoint is written, calling again continues). Throws naming the
// table, column, key or file on bad input, before anything trains.
bool run_experiment(const ExperimentOptions& options);

}  // namespace comorph::workflows
