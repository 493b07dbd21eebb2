// `comorph experiment --table 1|2 --config FILE --out runs/EXP`: every column
// of the paper's Table I or II as its own run directory, then the combined
// table beside the paper's and a full report (workflows/experiment.hpp).
#include <cstdlib>

#include "command_registry.hpp"
#include "cli_numbers.hpp"
#include "workflows/experiment.hpp"

namespace {

comorph::cli::CommandRegistration registration{[](CLI::App& app) {
  auto* ex = app.add_subcommand(
      "experiment", "train and evaluate every column of the paper's Table I or II, then the table beside the paper's");
  static comorph::workflows::ExperimentOptions options;
  ex->add_option("--table", options.table, "1: hierarchy vs fixed 2..10 modules; 2: TD3 vs SAC, 7/8 obstacles, mixed")
      ->required();
  ex->add_option("--config", options.config, "run config of every column (configs/quick.yaml, paper.yaml, ci.yaml)")
      ->required()
      ->check(CLI::ExistingFile);
  ex->add_option("--set", options.sets, "override a key of every column: --set trainer.episodes=100 (repeatable)");
  ex->add_option("--out", options.out, "experiment directory: one run directory per column, table-N.md, report/")
      ->required();
  ex->add_option("--only", options.only, "run only this column (e.g. fixed-4); the table shows what exists");
  ex->add_option("--eval-episodes", options.eval_episodes, "evaluation episodes per scenario (default: eval.episodes)")
      ->check(comorph::cli::whole_in(1, 1000000));
  ex->add_option("--eval-seed", options.eval_seed,
                 "first seed of the evaluation episodes (default: eval.seed); report figures from seeds no training used")
      ->check(comorph::cli::whole_in(0, 2000000000));
  ex->callback([] {
    if (!comorph::workflows::run_experiment(options)) std::exit(130);  // interrupted, checkpoint written
  });
}};

}  // namespace
