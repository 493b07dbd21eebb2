// `comorph export-mjcf`, `comorph physics-table`, `comorph demo`: the simulated
// robot and its scenario (src/sim, src/control, src/task).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <stdexcept>

#include "cli_numbers.hpp"
#include "command_registry.hpp"
#include "common/resources.hpp"
#include "sim/mjcf.hpp"
#include "sim/model.hpp"
#include "task/env_config.hpp"
#include "task/multitask_env.hpp"
#include "task/physics_table.hpp"
#include "task/scripted_pilot.hpp"

namespace {

using namespace comorph;

// CLI check of an option naming a value of enum E: "" or the names it takes.
template <class E>
std::string enum_name_check(const std::string& name) {
  E value;
  return enum_from_name(name, value) ? std::string() : "not one of " + enum_name_list<E>();
}

struct SimOptions {
  std::string config_dir;  // "": configs/sim of resource_dir()
  int modules = 4;
  double stair_height = 0;
  int obstacles = -1;
  std::uint64_t seed = 1;
  std::string variant = "standard";
  bool json = false;
  int seeds = 3;
  bool quick = false;
  int shed_to = 0;
  task::FlatSteering steering = task::FlatSteering::planned;
  task::StairSteering stair_steering = task::StairSteering::straight;
  int scan_columns = 24;  // the obstacle scan's rays when steering by it (the standard preset's)
  double noise = 0;       // std of Gaussian noise on the pilot's actions (the trainer's warmup_noise)
  int max_steps = 0;      // step cap (0: task.yaml's)
};

task::EnvConfig load_config(const std::string& dir) {
  return task::load_env_config(given_or_resource(dir, "configs/sim"));
}

// Limits of the scene options: the stair heights of configs/sim/scene.yaml
// (0..0.3 m) and seeds that every seed type in the scene code holds exactly.
constexpr double kMaxStairHeight = 0.3;
constexpr long long kMaxSeed = 1LL << 53;

std::string num(double v, int digits) {
  return std::isnan(v) ? std::string("-") : fmt::format("{:.{}f}", v, digits);
}
std::string json_num(double v, int digits) {
  return std::isnan(v) ? std::string("null") : fmt::format("{:.{}f}", v, digits);
}

void run_export(const SimOptions& o) {
  const task::EnvConfig c = load_config(o.config_dir);
  const sim::SceneLayout layout = sim::generate_scene(c.scene, o.seed, o.stair_height, o.obstacles,
                                                      sim::parse_variant(o.variant));
  const std::string xml = sim::build_mjcf(make_chain(o.modules), c.robot, c.scene, layout);
  sim::compile_mjcf(xml);  // never hand out a file MuJoCo would reject
  std::cout << xml;
}

void run_physics_table(const SimOptions& o) {
  const task::EnvConfig c = load_config(o.config_dir);
  task::PhysicsTableOptions opt;
  opt.seeds = o.seeds;
  if (o.quick) opt.modules = {2, 6};
  std::cerr << fmt::format(
      "physics-table: per row a stair-gait search over a2=a4 x a3 ({} x {} grid, seed 1000), then {} seeds; "
      "{} rows\n",
      opt.amplitudes.size(), opt.phases.size(), opt.seeds, opt.modules.size() * 3);
  const auto rows = task::physics_table(c, opt, [](int i, int total, const task::PhysicsRow& r) {
    std::cerr << fmt::format("  [{}/{}] {} modules, {:.2f} m: climbed {:.2f}\n", i, total, r.modules,
                             r.stair_height_m, r.climbed);
  });
  if (o.json) {
    std::cout << "[\n";
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const auto& r = rows[i];
      std::cout << fmt::format(
          "  {{\"modules\": {}, \"stair_height_m\": {:.3f}, \"climbed\": {:.3f}, \"time_s\": {}, "
          "\"energy_J\": {}, \"watts_per_module\": {}, \"turn_deg_s\": {:.1f}, "
          "\"gait\": {{\"a0\": {:.2f}, \"a2\": {:.2f}, \"a3\": {:.2f}, \"a4\": {:.2f}}}}}{}\n",
          r.modules, r.stair_height_m, r.climbed, json_num(r.time_s, 2), json_num(r.energy_J, 1),
          json_num(r.watts_per_module, 2), r.turn_deg_s, r.gait.speed, r.gait.amp_front, r.gait.phase,
          r.gait.amp_back, i + 1 < rows.size() ? "," : "");
    }
    std::cout << "]\n";
    return;
  }
  std::cout << fmt::format("{:>7} {:>14} {:>8} {:>8} {:>10} {:>16} {:>12}  {}\n", "modules", "stair_height_m",
                           "climbed", "time_s", "energy_J", "watts_per_module", "turn_deg_s",
                           "gait (a2=a4, a3)");
  for (const auto& r : rows)
    std::cout << fmt::format("{:>7} {:>14.2f} {:>8.2f} {:>8} {:>10} {:>16} {:>12.1f}  ({:+.2f}, {:+.2f})\n",
                             r.modules, r.stair_height_m, r.climbed, num(r.time_s, 2), num(r.energy_J, 1),
                             num(r.watts_per_module, 2), r.turn_deg_s, r.gait.amp_front, r.gait.phase);
}

void run_demo(const SimOptions& o) {
  task::EnvConfig c = load_config(o.config_dir);
  const bool scans = o.steering == task::FlatSteering::scan || o.stair_steering == task::StairSteering::scan;
  if (scans && c.robot.scan_columns == 0) c.robot.scan_columns = o.scan_columns;
  if (o.max_steps > 0) c.task.max_steps = o.max_steps;
  task::MultiTaskEnv env(c);
  task::EpisodeSpec spec;
  spec.seed = o.seed;
  spec.configuration = make_chain(o.modules);
  spec.stair_height = o.stair_height;
  spec.obstacles = o.obstacles;
  spec.variant = sim::parse_variant(o.variant);
  env.reset(spec);
  const sim::SceneLayout& s = env.world().layout();
  std::cout << fmt::format(
      "demo: {} modules, seed {}, stairs 3 x {:.2f} m, {} obstacles ({}), target at ({:.2f}, {:.2f}) m, "
      "start distance {:.2f} m\n",
      o.modules, o.seed, s.stair_height, s.obstacles.size(), comorph::name_of(s.variant), s.target_x,
      s.target_y, env.metrics().initial_distance_m);
  task::ScriptedPilot pilot;
  // The stair gait the physics-table search picks (full amplitude, wave lag -0.5).
  pilot.params().gait = {1.0f, 1.0f, -0.5f, 1.0f};
  pilot.params().flat_steering = o.steering;
  pilot.params().stair_steering = o.stair_steering;
  pilot.plan(env);
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  float action[control::kActionSize];
  control::MotionMode mode = env.mode(), last_mode = env.mode();
  int last_label = env.scene_label();
  double reward_sum = 0;
  std::cout << fmt::format("  t={:6.2f} s  event: start in {} mode, scene label {}\n", 0.0,
                           control::mode_name(mode), last_label);
  while (!env.done()) {
    pilot.act(env, action, mode);
    for (float& a : action) a = std::clamp(a + float(o.noise) * noise(rng), -1.0f, 1.0f);
    const task::StepOutcome& r = env.step(action, mode);
    reward_sum += r.reward;
    const double t = env.metrics().time_s;
    const double* head = env.world().module_pos(0);
    if (mode != last_mode)
      std::cout << fmt::format("  t={:6.2f} s  event: mode {} -> {}\n", t, control::mode_name(last_mode),
                               control::mode_name(mode));
    last_mode = mode;
    if (r.stairs_climbed_now) {
      std::cout << fmt::format("  t={:6.2f} s  event: stairs climbed (energy on stairs {:.1f} J)\n", t,
                               env.stairs_energy());
      if (o.shed_to >= kMinModules && o.shed_to < env.modules() && !env.done()) {
        const int before = env.modules();
        env.reconfigure(make_chain(o.shed_to));
        std::cout << fmt::format("  t={:6.2f} s  event: reconfigured {} -> {} modules (tail shed)\n", t, before,
                                 env.modules());
      }
    }
    if (r.scene_label != last_label)
      std::cout << fmt::format("  t={:6.2f} s  event: scene label {} -> {}\n", t, last_label, r.scene_label);
    last_label = r.scene_label;
    if (env.step_count() % 100 == 0 || env.done()) {
      const task::EpisodeMetrics m = env.metrics();
      std::cout << fmt::format(
          "  t={:6.2f} s  step {:4d}  pos ({:5.2f}, {:5.2f}, {:4.2f}) m  to target {:5.2f} m  energy {:7.1f} J "
          "({:4.1f} W per initial module)  R1 sum {:8.1f}\n",
          t, env.step_count(), head[0], head[1], head[2], m.initial_distance_m - m.distance_done_m, m.energy_J,
          m.energy_J / std::max(t, 1e-9) / env.initial_modules(), reward_sum);
    }
    if (env.done()) {
      const task::EpisodeMetrics m = env.metrics();
      std::cout << fmt::format("  t={:6.2f} s  event: {} ({})\n", t,
                               r.reason == task::Termination::success ? "target reached" : "episode ended",
                               task::termination_name(r.reason));
      std::cout << fmt::format(
          "result: {} after {} steps ({:.2f} s), energy {:.1f} J, T {:.3f}, E {:.4f}, D {:.3f}, F {:.3f}, "
          "R1 sum {:.1f}\n",
          task::termination_name(r.reason), m.steps, m.time_s, m.energy_J, m.T, m.E, m.D, m.F, reward_sum);
    }
  }
}

comorph::cli::CommandRegistration registration{[](CLI::App& app) {
  static SimOptions o;
  static const std::string modules_help = fmt::format("number of modules ({}..{})", kMinModules, kMaxModules);
  auto* exp = app.add_subcommand("export-mjcf", "write the scene with a chain robot as MJCF to stdout");
  exp->add_option("--modules,-n", o.modules, modules_help)->check(CLI::Range(kMinModules, kMaxModules));
  exp->add_option("--stair-height", o.stair_height, "m, step height (0 = drawn from the seed)")
      ->check(cli::finite_in(0, kMaxStairHeight));
  exp->add_option("--obstacles", o.obstacles, "K obstacles (-1 = scene default)")->check(cli::whole_in(-1, 50));
  exp->add_option("--seed", o.seed, "scene seed")->check(cli::whole_in(0, kMaxSeed));
  exp->add_option("--variant", o.variant, "standard | mixed");
  exp->add_option("--config-dir", o.config_dir, cli::kConfigDirHelp);
  exp->callback([] { run_export(o); });

  auto* table = app.add_subcommand("physics-table",
                                   "climbing success/time/energy per chain length and stair height (gait search)");
  table->add_flag("--json", o.json, "print JSON instead of a table");
  table->add_option("--seeds", o.seeds, "evaluation seeds per row")->check(CLI::Range(1, 50));
  table->add_flag("--quick", o.quick, "only 2 and 6 modules");
  table->add_option("--config-dir", o.config_dir, cli::kConfigDirHelp);
  table->callback([] { run_physics_table(o); });

  auto* demo = app.add_subcommand("demo", "a scripted controller drives the robot through the scenario");
  demo->add_option("--modules,-n", o.modules, modules_help)->check(CLI::Range(kMinModules, kMaxModules));
  demo->add_option("--seed", o.seed, "scene seed")->check(cli::whole_in(0, kMaxSeed));
  demo->add_option("--stair-height", o.stair_height, "m, step height (0 = drawn from the seed)")
      ->check(cli::finite_in(0, kMaxStairHeight));
  demo->add_option("--obstacles", o.obstacles, "K obstacles (-1 = scene default)")->check(cli::whole_in(-1, 50));
  demo->add_option("--variant", o.variant, "standard | mixed");
  demo->add_option("--shed-to", o.shed_to, "after the stairs, shed tail modules down to this many (0 = keep)")
      ->check(cli::whole_in(0, kMaxModules));
  static std::string steering = "planned";
  demo->add_option("--pilot-steering", steering,
                   "flat area: " + enum_name_list<task::FlatSteering>() +
                       " (a path on the true layout | towards the scan's open direction nearest the target)")
      ->check(enum_name_check<task::FlatSteering>);
  static std::string stair_steering = "straight";
  demo->add_option("--pilot-stair-steering", stair_steering,
                   "stairs: " + enum_name_list<task::StairSteering>() +
                       " (up the middle | around the obstacles the scan shows on the treads)")
      ->check(enum_name_check<task::StairSteering>);
  demo->add_option("--scan-columns", o.scan_columns,
                   "rays of the obstacle scan when the pilot steers by it, where the config has none")
      ->capture_default_str()
      ->check(cli::whole_in(1, 256));
  demo->add_option("--noise", o.noise, "std of Gaussian noise on the pilot's actions (action units; training uses 0.2)")
      ->check(cli::finite_in(0, 2));
  demo->add_option("--max-steps", o.max_steps, "step cap (0 = task.yaml's max_steps)")->check(cli::whole_in(0, 1000000));
  demo->add_option("--config-dir", o.config_dir, cli::kConfigDirHelp);
  demo->callback([] {
    enum_from_name(steering, o.steering);
    enum_from_name(stair_steering, o.stair_steering);
    run_demo(o);
  });
}};

}  // namespace
