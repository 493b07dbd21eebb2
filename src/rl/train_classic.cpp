#include "rl/train_classic.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "rl/classic/cartpole.hpp"
#include "rl/classic/pendulum.hpp"
#include "rl/registry.hpp"

namespace comorph::rl {

std::unique_ptr<Env> make_classic_env(const std::string& name) {
  if (name == "pendulum") return std::make_unique<PendulumEnv>();
  if (name == "cartpole") return std::make_unique<CartPoleEnv>();
  throw std::invalid_argument("unknown classic env \"" + name + "\" (pendulum or cartpole)");
}

std::unique_ptr<Learner> make_learner(const std::string& algorithm, const ObservationSpec& observation,
                                      const ActionSpec& action, const YAML::Node& config,
                                      const std::string& source, std::uint64_t seed) {
  const LearnerEntry& entry = learner_entry(algorithm);
  LearnerArgs args;
  args.observation = observation;
  args.action = action;
  args.seed = seed;
  args.config = entry.read_config(config, source);
  return make_learner(algorithm, args);
}

std::string classic_config_path(const std::string& env, const std::string& algorithm) {
  return rl_config_dir() + "/" + env + "_" + algorithm + ".yaml";
}

TrainStats train(Env& env, Learner& learner, std::int64_t steps,
                 const std::function<void(std::int64_t)>& on_step) {
  const auto start = std::chrono::steady_clock::now();
  TrainStats stats;
  Observation obs, next;
  allocate(env.observation_spec(), obs);
  allocate(env.observation_spec(), next);
  Action action;
  env.reset(obs);
  double episode_return = 0;
  for (std::int64_t t = 0; t < steps; ++t) {
    learner.act(obs, /*explore=*/true, action);
    const StepResult r = env.step(action, next);
    learner.store(obs, action, r.reward, next, r.terminated, r.truncated);
    episode_return += r.reward;
    if (r.terminated || r.truncated) {
      stats.episode_returns.push_back(episode_return);
      episode_return = 0;
      env.reset(obs);
    } else {
      std::swap(obs, next);
    }
    for (int u = learner.updates_due(); u > 0; --u) learner.update();
    if (on_step) on_step(t);
  }
  stats.steps = steps;
  stats.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

std::vector<double> evaluate(Env& env, Learner& learner, int episodes) {
  std::vector<double> returns;
  Observation obs;
  allocate(env.observation_spec(), obs);
  Action action;
  for (int e = 0; e < episodes; ++e) {
    env.reset(obs);
    double total = 0;
    for (;;) {
      learner.act(obs, /*explore=*/false, action);
      const StepResult r = env.step(action, obs);
      total += r.reward;
      if (r.terminated || r.truncated) break;
    }
    returns.push_back(total);
  }
  return returns;
}

ClassicResult run_classic(const ClassicOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  if (o.steps < 0) throw std::invalid_argument("--steps must be >= 0");
  std::unique_ptr<Env> env = make_classic_env(o.env);
  std::unique_ptr<Env> eval_env = make_classic_env(o.env);
  env->seed(o.seed);
  eval_env->seed(o.seed + 1000003);  // evaluation episodes differ from training ones
  const bool discrete = env->action_spec().kind == ActionKind::kDiscrete;
  if ((o.algorithm == "dqn") != discrete)
    throw std::invalid_argument(o.algorithm + " cannot act in " + env->name() +
                                (discrete ? ": discrete actions, use dqn"
                                          : ": continuous actions, use td3 or sac"));
  const std::string path = o.config_path.empty() ? classic_config_path(o.env, o.algorithm) : o.config_path;
  std::unique_ptr<Learner> learner = make_learner(
      o.algorithm, env->observation_spec(), env->action_spec(), load_yaml_file(path), path, o.seed);

  ClassicResult result;
  std::int64_t next_log = o.steps / 10;
  std::vector<double> recent;
  result.train = train(*env, *learner, o.steps, [&](std::int64_t t) {
    if (!o.log_progress || t + 1 != next_log) return;
    next_log += o.steps / 10;
    spdlog::info("step {}: {} episodes, {} updates, last loss {:.4g}", t + 1,
                 learner->counters().episodes, learner->counters().updates, learner->last_loss());
  });
  result.eval_returns = evaluate(*eval_env, *learner, o.eval_episodes);
  const double n = static_cast<double>(result.eval_returns.size());
  result.mean_return = std::accumulate(result.eval_returns.begin(), result.eval_returns.end(), 0.0) / n;
  double var = 0;
  for (double r : result.eval_returns) var += (r - result.mean_return) * (r - result.mean_return);
  result.std_return = std::sqrt(var / n);
  result.train_wall_s = result.train.wall_s;
  result.steps_per_s = result.train.wall_s > 0 ? o.steps / result.train.wall_s : 0;
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace comorph::rl
