// `comorph classic ...`: train a learner of src/rl on a classic control task
// (Pendulum-v1, CartPole-v1) and evaluate its greedy policy.
#include <fmt/format.h>

#include <iostream>

#include "cli_numbers.hpp"
#include "command_registry.hpp"
#include "rl/learner.hpp"
#include "rl/train_classic.hpp"

namespace {

comorph::cli::CommandRegistration registration{[](CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "classic", "train TD3/SAC/DQN on Pendulum-v1 or CartPole-v1, then evaluate the greedy "
                 "policy over 10 episodes");
  static comorph::rl::ClassicOptions options;
  static bool json = false;
  static int threads = 1;
  cmd->add_option("--env", options.env, "pendulum | cartpole")
      ->required()
      ->check(CLI::IsMember({"pendulum", "cartpole"}));
  cmd->add_option("--algo", options.algorithm, "td3 | sac | dqn")
      ->required()
      ->check(CLI::IsMember({"td3", "sac", "dqn"}));
  cmd->add_option("--steps", options.steps, "training environment steps")
      ->required()
      ->check(comorph::cli::whole_in(1, 1000000000));
  cmd->add_option("--seed", options.seed, "random seed (env, learner, networks)")
      ->required()
      ->check(comorph::cli::whole_in(0, 2000000000));
  cmd->add_option("--config", options.config_path,
                  "hyperparameter YAML (default: configs/rl/<env>_<algo>.yaml)");
  cmd->add_option("--eval-episodes", options.eval_episodes, "greedy evaluation episodes")
      ->capture_default_str()
      ->check(comorph::cli::whole_in(1, 1000000));
  cmd->add_option("--threads", threads, "torch intra-op threads (1 is fastest for these nets)")
      ->capture_default_str()
      ->check(comorph::cli::whole_in(1, 64));
  cmd->add_flag("--json", json, "print one JSON object: mean_return, std_return, steps_per_s, wall_s");
  cmd->callback([] {
    comorph::rl::set_torch_threads(threads, 1);
    options.log_progress = !json;
    const comorph::rl::ClassicResult r = comorph::rl::run_classic(options);
    if (json) {
      std::cout << fmt::format(
          "{{\"env\": \"{}\", \"algo\": \"{}\", \"steps\": {}, \"seed\": {}, \"mean_return\": {:.6g}, "
          "\"std_return\": {:.6g}, \"steps_per_s\": {:.6g}, \"wall_s\": {:.6g}}}\n",
          options.env, options.algorithm, options.steps, options.seed, r.mean_return, r.std_return,
          r.steps_per_s, r.wall_s);
    } else {
      std::cout << fmt::format(
          "{} / {}, {} steps, seed {}\n"
          "greedy return over {} episodes: mean {:.2f}, std {:.2f}\n"
          "training: {:.1f} steps/s ({:.1f} s), wall time {:.1f} s\n",
          options.env, options.algorithm, options.steps, options.seed, r.eval_returns.size(),
          r.mean_return, r.std_return, r.steps_per_s, r.train_wall_s, r.wall_s);
    }
  });
}};

}  // namespace
