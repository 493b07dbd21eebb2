// The whole trainer's throughput for a preset (docs/coopt.md, "Throughput"),
// as ratios measured in one run:
//   - the trainer's control steps/s over --steps control steps (whole
//     episodes, the run's own seeds, writing episodes.csv as `comorph train`
//     does, ending with a checkpoint as an interrupted run does);
//   - each side alone on the same preset (coopt::measure_side_rates, once
//     before the trainer and once after, their mean rate): the
//     acting side (env, acting copy, pilot, scene source, DQN) and the motion
//     learner (store + updates); bound fraction = trainer / the slower side
//     (N simulation threads: N times the acting side, and no more work than
//     the cores can do; without a learner thread: / the rate of both sides
//     one after the other);
//   - each thread's share of the trainer's wall time (coopt::TrainerTiming);
//   - the checkpoint: s for one with a full motion replay, s for the next one
//     after checkpoint_interval episodes of new transitions, and that next
//     one's share of the wall time of checkpoint_interval episodes.
// Usage: bench_trainer [--config configs/standard.yaml] [--steps 50000] [--set k=v ...] [--json]
//        [--no-checkpoint-cost] [--trainer-only]
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "common/heap.hpp"
#include "common/resources.hpp"
#include "coopt/config.hpp"
#include "coopt/trainer.hpp"

namespace fs = std::filesystem;
using namespace comorph;

namespace {

double load_average() {
  double load[1] = {0};
  return getloadavg(load, 1) == 1 ? load[0] : -1.0;
}

// The fractions of the trainer's wall time (keys of the JSON's `share`).
// Acting thread: all but motion_updates and learner_idle add up to 1 (with a
// learner thread; without one, motion_updates is on the acting thread too).
nlohmann::ordered_json shares(const coopt::TrainerTiming& t, bool learner_thread) {
  const double w = t.wall_s;
  nlohmann::ordered_json s;
  s["env_step"] = t.env_step_s / w;
  s["env_reset"] = t.env_reset_s / w;
  s["acting"] = t.acting_s / w;
  s["handover"] = t.handover_s / w;
  s["waiting"] = t.waiting_s / w;
  s["dqn"] = t.dqn_s / w;
  s["classifier"] = t.classifier_s / w;
  s["evaluation"] = t.evaluation_s / w;
  s["checkpoint"] = t.checkpoint_s / w;
  s["logging"] = t.logging_s / w;
  s["other"] = t.other_s / w;
  s["motion_updates"] = (learner_thread ? t.learner_busy_s : t.motion_updates_s) / w;
  s["learner_idle"] = learner_thread ? 1.0 - t.learner_busy_s / w : 0.0;
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  comorph::keep_freed_memory_for_reuse();  // as comorph does
  CLI::App app{"Throughput of the hierarchical trainer for a preset: steps/s, each side alone, shares of wall time"};
  std::string config_path = resource_path("configs/quick.yaml");
  std::vector<std::string> sets;
  std::int64_t steps = 20000;
  bool json = false, skip_checkpoint = false, trainer_only = false;
  app.add_option("--config", config_path, "preset (default configs/quick.yaml)")->check(CLI::ExistingFile);
  app.add_option("--set", sets, "config override key=value, as in `comorph train`");
  app.add_option("--steps", steps, "control steps of the trainer and of each side alone (default 20000)")
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{1000000000}));
  app.add_flag("--json", json, "print one JSON object instead of text");
  app.add_flag("--no-checkpoint-cost", skip_checkpoint, "skip the full-replay checkpoint measurement");
  app.add_flag("--trainer-only", trainer_only,
               "the trainer and its shares only: no side rates, no bound fraction (for the DQN refit, where "
               "the motion learner has nothing to learn)");
  CLI11_PARSE(app, argc, argv);

  try {
    const coopt::CooptConfig config = coopt::load_coopt_config(config_path, sets);
    const double load_start = load_average();
    const fs::path scratch = fs::temp_directory_path() / fmt::format("bench_trainer-{}", getpid());
    fs::remove_all(scratch);
    const std::string run_dir = (scratch / "run").string();
    fs::create_directories(run_dir);

    // 1. Each side alone before the trainer, and again after it (2.): this
    //    machine's speed drifts by up to 1.5x between minutes, and a drift
    //    that is linear in time cancels in the mean over the two.
    const coopt::SideRates before = trainer_only ? coopt::SideRates{} : coopt::measure_side_rates(config, steps);

    // 2. The trainer, stopped after the episode that reaches --steps.
    std::atomic<bool> stop{false};
    std::int64_t done = 0;
    int episodes = 0;
    coopt::TrainerCallbacks callbacks;
    callbacks.on_episode = [&](const coopt::EpisodeLog& l) {
      done += l.steps;
      ++episodes;
      if (done >= steps) stop = true;
    };
    coopt::TrainerTiming timing;
    std::int64_t trainer_steps = 0;
    {
      coopt::Trainer trainer(config, run_dir, callbacks);
      trainer.run(&stop);
      timing = trainer.timing();
      trainer_steps = trainer.env_steps();
    }
    const double steps_per_s = static_cast<double>(trainer_steps) / timing.wall_s;

    // 3. Each side alone again.
    const coopt::SideRates after = trainer_only ? coopt::SideRates{} : coopt::measure_side_rates(config, steps);
    // Each side's rate over both of its runs (the same steps: steps over the summed time).
    auto both = [](double a, double b) { return a > 0 && b > 0 ? 2.0 / (1.0 / a + 1.0 / b) : 0.0; };
    coopt::SideRates sides = after;
    sides.acting_steps_per_s = both(before.acting_steps_per_s, after.acting_steps_per_s);
    sides.learner_steps_per_s = both(before.learner_steps_per_s, after.learner_steps_per_s);
    // With a learner thread: the slower of the acting side (N simulation
    // threads act N times as fast at best) and the learner, and the cores cap
    // the sum of both sides' work (cores / CPU time of a step's acting and
    // learning). Without one the learner runs while the simulation waits.
    const int sims = config.trainer.simulation_threads;
    const double cores = std::max(1u, std::thread::hardware_concurrency());
    const double acting = std::min<double>(sims, cores) * sides.acting_steps_per_s;
    const double both_s = 1.0 / sides.acting_steps_per_s + 1.0 / sides.learner_steps_per_s;
    const double bound = config.trainer.learner_thread
                             ? std::min({acting, sides.learner_steps_per_s, cores / both_s})
                             : 1.0 / (1.0 / acting + 1.0 / sides.learner_steps_per_s);

    // 4. Checkpoints: one with the motion replay full, then one after
    //    checkpoint_interval episodes of the trainer's mean length.
    const int interval = config.trainer.checkpoint_interval;
    const double steps_per_episode = static_cast<double>(trainer_steps) / episodes;
    const double episode_s = (timing.wall_s - timing.checkpoint_s) / episodes;
    const std::int64_t replay =
        config.trainer.motion_algo == "sac" ? config.sac.buffer_size : config.td3.buffer_size;
    const auto new_transitions = static_cast<std::int64_t>(interval * steps_per_episode);
    coopt::CheckpointCost cost;
    if (!skip_checkpoint && !trainer_only) {
      const std::string dir = (scratch / "checkpoint-cost").string();
      fs::create_directories(dir);
      cost = coopt::measure_checkpoint_cost(config, dir, replay, new_transitions);
    }
    const double checkpoint_share = cost.next_s / (cost.next_s + interval * episode_s);
    const double load_end = load_average();
    fs::remove_all(scratch);

    nlohmann::ordered_json out;
    out["config"] = config_path;
    out["steps"] = trainer_steps;
    out["episodes"] = episodes;
    out["learner_thread"] = config.trainer.learner_thread;
    out["simulation_threads"] = config.trainer.simulation_threads;
    out["steps_per_s"] = steps_per_s;
    if (!trainer_only) {
      out["env_only_steps_per_s"] = sides.acting_steps_per_s;
      out["learner_only_steps_per_s"] = sides.learner_steps_per_s;
      out["bound_fraction"] = steps_per_s / bound;
      out["sides_before_after"] = {{"env_only_steps_per_s", {before.acting_steps_per_s, after.acting_steps_per_s}},
                                   {"learner_only_steps_per_s", {before.learner_steps_per_s, after.learner_steps_per_s}}};
    }
    out["share"] = shares(timing, config.trainer.learner_thread);
    out["checkpoints_in_run"] = timing.checkpoints;
    if (!skip_checkpoint && !trainer_only) {
      out["checkpoint"] = {{"replay_transitions", replay},
                           {"full_replay_s", cost.first_s},
                           {"new_transitions", new_transitions},
                           {"next_s", cost.next_s},
                           {"interval_episodes", interval},
                           {"share_at_interval", checkpoint_share}};
    }
    out["load_average"] = {load_start, load_end};
    if (json) {
      fmt::print("{}\n", out.dump());
      return 0;
    }
    fmt::print("{}: {} control steps in {} episodes, learner thread {}, {} simulation thread(s)\n", config_path,
               trainer_steps, episodes, config.trainer.learner_thread ? "on" : "off",
               config.trainer.simulation_threads);
    fmt::print("trainer             {:8.0f} control steps/s ({:.1f} s wall)\n", steps_per_s, timing.wall_s);
    if (!trainer_only) {
      fmt::print("acting side alone   {:8.0f} control steps/s ({} steps: env, acting copy, pilot, scene, DQN; "
                 "{:.0f} before the trainer, {:.0f} after)\n",
                 sides.acting_steps_per_s, sides.acting_steps, before.acting_steps_per_s, after.acting_steps_per_s);
      fmt::print("learner alone       {:8.0f} control steps/s ({} steps after learning_starts: store + updates; "
                 "{:.0f} before, {:.0f} after)\n",
                 sides.learner_steps_per_s, sides.learner_steps, before.learner_steps_per_s,
                 after.learner_steps_per_s);
      fmt::print("bound fraction      {:8.2f} (trainer / {})\n", steps_per_s / bound,
                 config.trainer.learner_thread ? "the slower side" : "both sides one after the other");
    }
    fmt::print("share of the trainer's wall time:\n");
    for (const auto& [key, value] : out["share"].items()) fmt::print("  {:<16} {:6.3f}\n", key, value.get<double>());
    if (!skip_checkpoint && !trainer_only)
      fmt::print("checkpoint: {:.2f} s with {} transitions in the motion replay; the next after {} more "
                 "({} episodes of {:.0f} steps): {:.2f} s = {:.2f} % of those episodes' {:.0f} s\n",
                 cost.first_s, replay, new_transitions, interval, steps_per_episode, cost.next_s,
                 100.0 * checkpoint_share, interval * episode_s);
    fmt::print("load average {:.2f} at the start, {:.2f} at the end\n", load_start, load_end);
    return 0;
  } catch (const std::exception& e) {
    fmt::print(stderr, "bench_trainer: {}\n", e.what());
    return 1;
  }
}
