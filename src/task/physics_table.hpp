// The physics table: for each chain length and stair height, a stair-mode gait
// found by a small grid search (not learned), then its success rate, time,
// energy and power over a few seeds; plus each chain's turning rate on flat
// ground. It is the evidence that the physics makes the paper's trade-off real.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "task/env_config.hpp"
#include "task/scripted_pilot.hpp"

namespace comorph::task {

struct ClimbTrial {
  bool climbed = false;
  double time_s = 0;     // s until all modules are on the top (or until the trial stopped)
  double energy_J = 0;   // J drawn until then
  double progress_m = 0; // m, furthest x of the last module past its start
  Termination reason = Termination::none;
};

struct PhysicsTableOptions {
  std::vector<int> modules{2, 4, 6, 8, 10};
  std::vector<double> heights{};  // m; empty = the scene's three heights
  int seeds = 3;                  // evaluation seeds per row (the search uses another one)
  double time_limit_s = 25.0;     // s of simulated time per trial
  double stuck_time_s = 4.0;      // s without 1 cm of progress ends a trial
  std::vector<float> amplitudes{-1.0f, 0.0f, 1.0f};   // a2 = a4 candidates
  std::vector<float> phases{-0.5f, -0.2f, 0.2f};      // a3 candidates
  double turn_time_s = 3.0;       // s of turning on the spot for the turn rate
};

struct PhysicsRow {
  int modules = 0;
  double stair_height_m = 0;
  double climbed = 0;            // success rate over the seeds, 0..1
  double time_s = 0;             // mean over successful seeds (NaN when none)
  double energy_J = 0;           // mean over successful seeds (NaN when none)
  double watts_per_module = 0;   // energy_J / time_s / modules (NaN when none)
  double turn_deg_s = 0;         // yaw rate on flat ground at a1 = 1, a0 = 0 (deg/s)
  StairGait gait;                // the gait found by the search
};

// One climbing trial: stairs only (no obstacles), the pilot in stair mode with `gait`.
// `cache` (optional) shares compiled models between trials.
ClimbTrial run_climb_trial(const EnvConfig& config, int modules, double stair_height, std::uint64_t seed,
                           const StairGait& gait, const PhysicsTableOptions& options,
                           std::shared_ptr<sim::ModelCache> cache = nullptr);
// Yaw rate (deg/s) of a chain turning on the spot in flat mode on flat ground.
double measure_turn_rate(const EnvConfig& config, int modules, double seconds,
                         std::shared_ptr<sim::ModelCache> cache = nullptr);

// progress(row_index, total_rows, row) is called after each row (may be empty).
std::vector<PhysicsRow> physics_table(const EnvConfig& config, const PhysicsTableOptions& options,
                                      const std::function<void(int, int, const PhysicsRow&)>& progress = {});

}  // namespace comorph::task
