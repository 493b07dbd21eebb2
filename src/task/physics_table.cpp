#include "task/physics_table.hpp"

#include <cmath>
#include <limits>

namespace comorph::task {

ClimbTrial run_climb_trial(const EnvConfig& config, int modules, double stair_height, std::uint64_t seed,
                           const StairGait& gait, const PhysicsTableOptions& o,
                           std::shared_ptr<sim::ModelCache> cache) {
  EnvConfig c = config;
  c.task.max_steps = int(o.time_limit_s / c.robot.control_period) + 1;
  MultiTaskEnv env(c, std::move(cache));
  EpisodeSpec spec;
  spec.seed = seed;
  spec.configuration = make_chain(modules);
  spec.stair_height = stair_height;
  spec.obstacles = 0;
  env.reset(spec);
  PilotParams pp;
  pp.gait = gait;
  ScriptedPilot pilot(pp);
  float action[control::kActionSize];
  control::MotionMode mode;
  ClimbTrial t;
  const double start_tail = env.world().module_pos(modules - 1)[0];
  double best = 0;
  int best_step = 0;
  const int stuck_steps = int(o.stuck_time_s / c.robot.control_period);
  while (!env.done()) {
    pilot.act(env, action, mode);
    const StepOutcome& r = env.step(action, control::MotionMode::stair);
    const double progress = env.world().module_pos(modules - 1)[0] - start_tail;
    if (progress > best + 0.01) best = progress, best_step = env.step_count();
    if (r.stairs_climbed_now) {
      t.climbed = true;
      break;
    }
    if (r.terminated || r.truncated) t.reason = r.reason;
    if (env.step_count() - best_step > stuck_steps) break;
  }
  const EpisodeMetrics m = env.metrics();
  t.time_s = m.time_s;
  t.energy_J = m.energy_J;
  t.progress_m = best;
  return t;
}

double measure_turn_rate(const EnvConfig& config, int modules, double seconds,
                         std::shared_ptr<sim::ModelCache> cache) {
  const EnvConfig& c = config;
  MultiTaskEnv env(c, std::move(cache));
  EpisodeSpec spec;
  spec.configuration = make_chain(modules);
  spec.obstacles = 0;
  env.reset(spec);
  const float action[control::kActionSize] = {0.0f, 1.0f, -1.0f, 0.0f, -1.0f};
  const int steps = int(seconds / c.robot.control_period);
  double last = env.world().heading(), total = 0;
  for (int i = 0; i < steps && !env.done(); ++i) {
    env.step(action, control::MotionMode::flat);
    double h = env.world().heading(), d = h - last;
    while (d > M_PI) d -= 2 * M_PI;
    while (d < -M_PI) d += 2 * M_PI;
    total += d;
    last = h;
  }
  return total * 180.0 / M_PI / (steps * c.robot.control_period);
}

std::vector<PhysicsRow> physics_table(const EnvConfig& config, const PhysicsTableOptions& o,
                                      const std::function<void(int, int, const PhysicsRow&)>& progress) {
  std::vector<double> heights = o.heights;
  if (heights.empty())
    heights = {config.scene.stair_height_a, config.scene.stair_height_b, config.scene.stair_height_c};
  std::vector<StairGait> candidates;
  for (float amp : o.amplitudes)
    for (float phase : o.phases) {
      candidates.push_back({1.0f, amp, phase, amp});
      if (amp <= -1.0f) break;  // no wave: the phase does not matter
    }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<PhysicsRow> rows;
  const int total = int(o.modules.size() * heights.size());
  auto cache = std::make_shared<sim::ModelCache>(config.robot, config.scene);
  for (int n : o.modules) {
    const double turn = measure_turn_rate(config, n, o.turn_time_s, cache);
    for (double h : heights) {
      // Search on seed 1000 (not an evaluation seed): climbed first, then time.
      StairGait best = candidates.front();
      double best_score = -1e18;
      for (const StairGait& g : candidates) {
        const ClimbTrial t = run_climb_trial(config, n, h, 1000, g, o, cache);
        const double score = t.climbed ? 1000.0 - t.time_s : t.progress_m;
        if (score > best_score) best_score = score, best = g;
      }
      PhysicsRow row;
      row.modules = n;
      row.stair_height_m = h;
      row.turn_deg_s = turn;
      row.gait = best;
      int ok = 0;
      double time = 0, energy = 0;
      for (int s = 0; s < o.seeds; ++s) {
        const ClimbTrial t = run_climb_trial(config, n, h, std::uint64_t(s + 1), best, o, cache);
        if (t.climbed) ++ok, time += t.time_s, energy += t.energy_J;
      }
      row.climbed = double(ok) / o.seeds;
      row.time_s = ok ? time / ok : nan;
      row.energy_J = ok ? energy / ok : nan;
      row.watts_per_module = ok ? row.energy_J / row.time_s / n : nan;
      rows.push_back(row);
      if (progress) progress(int(rows.size()), total, row);
    }
  }
  return rows;
}

}  // namespace comorph::task
