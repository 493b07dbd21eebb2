// `comorph train` (hierarchical co-optimization, fixed baselines, SAC) and
// `comorph eval` (greedy policies on the paper's protocol); the work is in
// run_steps.cpp, shared with `comorph experiment`.
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "cli_numbers.hpp"
#include "cli_scenario.hpp"
#include "morphology/configuration.hpp"
#include "command_registry.hpp"
#include "coopt/trainer.hpp"
#include "workflows/run_steps.hpp"

namespace {

comorph::cli::CommandRegistration registration{[](CLI::App& app) {
  auto* tr = app.add_subcommand("train", "hierarchical co-optimization (or a fixed/SAC baseline) into a run directory");
  static std::string config, out, resume;
  static std::vector<std::string> sets;
  tr->add_option("--config", config, "run config (configs/quick.yaml, paper.yaml, ci.yaml)");
  tr->add_option("--set", sets, "override a key: --set trainer.episodes=10 (dotted path, repeatable)");
  tr->add_option("--out", out, "new run directory, e.g. runs/quick");
  tr->add_option("--resume", resume, "continue the run in this directory from its last checkpoint");
  tr->callback([] {
    // Under `mpirun -np K`: rank 0 trains, ranks 1..K-1 are its actors.
    const comorph::coopt::MpiJob mpi;
    bool finished = true;
    try {
      if (mpi.rank() > 0) {
        comorph::workflows::serve_train_actor(config, sets, resume);
        return;
      }
      finished = comorph::workflows::train_run(config, sets, out, resume, false, mpi.joined());
    } catch (const std::exception& e) {
      if (!mpi.joined()) throw;
      std::fprintf(stderr, "comorph: error on rank %d of the MPI job: %s\n", mpi.rank(), e.what());
      mpi.abort(1);
    }
    if (finished) return;
    const std::string launcher = mpi.joined() ? "mpirun -np " + std::to_string(mpi.size()) + " " : "";
    std::fprintf(stderr, "continue with: %scomorph train --resume %s\n", launcher.c_str(),
                 (resume.empty() ? out : resume).c_str());
    std::fflush(stderr);
    std::exit(130);  // interrupted: a calling script (make run) stops here too
  });

  auto* ev = app.add_subcommand("eval", "greedy evaluation of a trained run (writes eval-<scenario>.json)");
  static std::string run, scenario = "default";
  static int episodes = 0, seed = -1, workers = 0, forced_modules = 0;
  ev->add_option("--run", run, "run directory")->required();
  comorph::cli::add_scenario_option(ev, scenario);
  // The same ranges as the config's eval section (coopt/config.cpp).
  ev->add_option("--episodes", episodes, "episodes (default: eval.episodes of the run's config)")
      ->check(comorph::cli::whole_in(1, 1000000));
  ev->add_option("--seed", seed, "seed of episode 0 (episode i: seed + i; default: eval.seed)")
      ->check(comorph::cli::whole_in(0, 2000000000));
  ev->add_option("--workers", workers, "threads (default: eval.workers; 0 there = one per core); results do not depend on it")
      ->check(comorph::cli::whole_in(1, 256));
  ev->add_option("--modules", forced_modules,
                 "drive a fixed chain of this many modules with the run's motion model (no configuration model, "
                 "no shedding): what the motion model can do with each body; writes eval-<scenario>-modules<N>.*")
      ->check(comorph::cli::whole_in(comorph::kMinModules, comorph::kMaxModules));
  static bool pilot_drives = false;
  ev->add_flag("--pilot", pilot_drives,
               "the scripted pilot drives (as the run's training configured it, without noise) instead of the motion "
               "model: the hand-written controller's figures; writes eval-<scenario>[-modules<N>]-pilot.*");
  ev->callback([] { comorph::workflows::eval_run(run, scenario, episodes, seed, workers, forced_modules, pilot_drives); });

  auto* ex = app.add_subcommand("export", "copy a trained run's policies (no replay buffers) and logs, e.g. into results/");
  static std::string export_run, export_out;
  ex->add_option("--run", export_run, "trained run directory")->required();
  ex->add_option("--out", export_out, "destination directory, e.g. results/standard-hier-td3")->required();
  ex->callback([] { comorph::workflows::export_run(export_run, export_out); });
}};

}  // namespace
