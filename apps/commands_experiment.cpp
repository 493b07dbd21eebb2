// `comorph experiment --table 1|2 --config FILE --out runs/EXP [--seeds 1-3]`:
// every column of the paper's Table I or II, for each training seed, as its
// own run directory, then the combined table beside the paper's and a full
// report; or the same runs as a job list (GNU parallel) or a Slurm array job,
// and the table collected from what exists (workflows/experiment.hpp).
#include <cstdlib>

#include "command_registry.hpp"
#include "cli_numbers.hpp"
#include "workflows/experiment.hpp"

namespace {

comorph::cli::CommandRegistration registration{[](CLI::App& app) {
  auto* ex = app.add_subcommand(
      "experiment", "train and evaluate every column of the paper's Table I or II, then the table beside the paper's");
  static comorph::workflows::ExperimentOptions options;
  static std::string seeds;
  ex->add_option("--table", options.table, "1: hierarchy vs fixed 2..10 modules; 2: TD3 vs SAC, 7/8 obstacles, mixed")
      ->required();
  ex->add_option("--config", options.config,
                 "run config of every column (configs/quick.yaml, paper.yaml, ci.yaml); not needed with --collect")
      ->check(CLI::ExistingFile);
  ex->add_option("--set", options.sets, "override a key of every column: --set trainer.episodes=100 (repeatable)");
  ex->add_option("--out", options.out,
                 "experiment directory: one run directory per column (COLUMN-seed-S with --seeds), table-N.md, report/")
      ->required();
  ex->add_option("--only", options.only, "run only this column (e.g. fixed-4); the table shows what exists");
  static CLI::Option* seeds_option = nullptr;
  seeds_option = ex->add_option("--seeds", seeds,
                 "training seeds, e.g. 1-3 or 1,2,5: one run per column and seed, the table's figures their mean "
                 "[min, max] (default: one run per column, the config's trainer.seed)");
  ex->add_option("--eval-episodes", options.eval_episodes, "evaluation episodes per scenario (default: eval.episodes)")
      ->check(comorph::cli::whole_in(1, 1000000));
  ex->add_option("--eval-seed", options.eval_seed,
                 "first seed of the evaluation episodes (default: eval.seed); report figures from seeds no training used")
      ->check(comorph::cli::whole_in(0, 2000000000));
  auto* jobs = ex->add_option("--jobs", options.jobs_file,
                              "train nothing; write one command line per run (column x seed) to FILE, for "
                              "`parallel -j N < FILE`");
  auto* slurm = ex->add_option("--slurm", options.slurm_file,
                               "train nothing; write a Slurm array job to FILE, one task per run, for "
                               "`sbatch --array=0-K%M FILE`");
  auto* collect = ex->add_flag("--collect", options.collect,
                               "train nothing; the table and report from the runs that exist, naming what is missing");
  ex->add_option("--runs", options.runs,
                 "with --collect: these run directories (matched to the columns by their run.yaml) instead of --out's")
      ->needs(collect);
  auto* no_table = ex->add_flag("--no-table", options.no_table,
                                "train and evaluate only, no table or report (what each job of --jobs/--slurm runs)");
  collect->excludes(jobs)->excludes(slurm)->excludes(no_table);
  ex->callback([] {
    if (seeds_option->count() > 0) options.seeds = comorph::workflows::parse_seeds(seeds);
    if (!comorph::workflows::run_experiment(options)) std::exit(130);  // interrupted, checkpoint written
  });
}};

}  // namespace
