// The steps of a run directory's life, shared by `comorph train`, `eval` and
// `experiment`: train (new or resumed) and evaluate. The run-directory layout
// is docs/report.md's.
#pragma once

#include <string>
#include <vector>

#include "report/metrics.hpp"

namespace comorph::workflows {

// Trains a new run into `out` (config file + `--set`s) or, when `resume` is
// given, continues that run from its last checkpoint. SIGINT/SIGTERM finish
// the current episode (with trainer.simulation_threads > 1: the current block,
// at most checkpoint_interval episodes) and write a checkpoint; returns false then, true when
// every episode is done. The run directory is locked (common/run_lock.hpp)
// for the whole training unless `locked_by_caller` (`comorph experiment`
// holds the column's lock itself). A resume is refused when episodes.csv or
// evaluations.csv lack rows the checkpoint counts or have damaged ones.
// mpi_actors: this process is rank 0 of an MPI job (coopt::MpiJob) and the
// other ranks are its actors (each running serve_train_actor).
bool train_run(const std::string& config_path, const std::vector<std::string>& sets, const std::string& out,
               const std::string& resume, bool locked_by_caller = false, bool mpi_actors = false);
// An actor rank of `comorph train` under mpirun: the run's config from the
// same arguments as rank 0's (config file + `--set`s, or the resumed run's
// config.yaml), then coopt::serve_actor_rank until rank 0 ends the run.
void serve_train_actor(const std::string& config_path, const std::vector<std::string>& sets,
                       const std::string& resume);

// The log a job of `comorph experiment --jobs/--slurm` appends to in its run
// directory: like the lock file, there before the training starts.
inline constexpr const char* kJobLogFile = "job.log";

// True when `dir` is missing or holds nothing but a run lock file and a job log.
bool is_empty_run_dir(const std::string& dir);
// Removes everything in `dir` but the lock file (that a caller may hold) and the job log.
void clear_run_dir(const std::string& dir);

// Greedy evaluation of a trained run on the paper's protocol: writes
// eval-<scenario>.json and eval-<scenario>-episodes.csv into the run
// directory and prints the summary. episodes/seed/workers <= 0 (seed < 0):
// the run config's eval section. forced_modules > 0: the run's motion model
// drives a fixed chain of that many modules (EvalRequest::forced_modules);
// the files are then eval-<scenario>-modules<N>.json and -episodes.csv.
// pilot_drives: the run's scripted pilot drives (EvalRequest::pilot_drives),
// and the names end in -pilot.
report::EvalSummary eval_run(const std::string& run_dir, const std::string& scenario, int episodes, int seed,
                         int workers, int forced_modules = 0, bool pilot_drives = false);

// Copies what `eval`, `render` and `report` need of a trained run into `out`
// (config.yaml, run.yaml, episodes.csv.gz: the log rounded to the report's digits and gzipped,
// evaluations.csv, eval-*.json) with a checkpoint/ of the acting networks only (no replay, no
// optimizers): a trained policy small enough to ship in the repository. The
// copy evaluates like the run; it cannot resume training. Returns its bytes.
std::uintmax_t export_run(const std::string& run_dir, const std::string& out);

}  // namespace comorph::workflows
