// Each side of the trainer alone, and the cost of its checkpoints
// (bench/coopt/bench_trainer; docs/coopt.md, "Throughput").
#include <torch/torch.h>

#include <chrono>
#include <random>
#include <stdexcept>

#include "coopt/actor_threads.hpp"
#include "coopt/learner_host.hpp"
#include "coopt/segment.hpp"
#include "coopt/trainer.hpp"
#include "rl/learner.hpp"

namespace comorph::coopt {

SideRates measure_side_rates(const CooptConfig& config, std::int64_t steps) {
  if (steps < 1) throw std::invalid_argument("measure_side_rates: steps must be >= 1");
  // One actor and a host that records its transitions instead of learning them.
  LearnerHost host(config, "", {}, 1);
  ActorThreads actor(config, 1, {});
  // The last episode may run past `steps` by up to a whole episode.
  std::vector<Transition> record;
  allocate_transitions(config, record, static_cast<std::size_t>(steps + config.env.task.max_steps + 1));
  host.record_into(&record);
  SideRates rates;
  Clock::time_point start = Clock::now();
  act_and_learn(host, actor, [&] { return static_cast<std::int64_t>(host.recorded()) >= steps; });
  const std::size_t recorded = host.recorded();
  rates.acting_steps = static_cast<std::int64_t>(recorded);
  rates.acting_steps_per_s =
      static_cast<double>(recorded) / std::chrono::duration<double>(Clock::now() - start).count();

  // The learner alone on those transitions; its first updates start the clock
  // (before learning_starts a step costs only the store).
  rl::Learner& l = *host.state().motion;
  std::size_t i = 0;
  bool learning = false;
  auto learn = [&](const Transition& tr) {
    l.store(tr.obs, tr.action, tr.reward, tr.next, tr.terminated, tr.truncated, tr.steps);
    int due = l.updates_due();
    learning = learning || due > 0;
    for (; due > 0; --due) l.update();
  };
  while (i < recorded && !learning) learn(record[i++]);
  if (!learning)
    throw std::runtime_error("measure_side_rates: " + std::to_string(recorded) +
                             " control steps never reached the motion learner's learning_starts; give more steps");
  const std::size_t first_timed = i;
  start = Clock::now();
  while (i < recorded) learn(record[i++]);
  rates.learner_steps = static_cast<std::int64_t>(recorded - first_timed);
  const double learner_s = std::chrono::duration<double>(Clock::now() - start).count();
  rates.learner_steps_per_s = learner_s > 0 ? static_cast<double>(rates.learner_steps) / learner_s : 0.0;
  return rates;
}

CheckpointCost measure_checkpoint_cost(const CooptConfig& config, const std::string& run_dir,
                                       std::int64_t transitions, std::int64_t new_transitions) {
  LearnerHost host(config, run_dir, {}, 1);
  TrainingState& state = host.state();
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  rl::Observation o, next, co, cnext;
  rl::allocate(motion_spec(config), o);
  rl::allocate(motion_spec(config), next);
  rl::allocate(config_spec(config), co);
  rl::allocate(config_spec(config), cnext);
  rl::Action a, ca;
  a.continuous.assign(control::kActionSize, 0.5f);
  if (config.trainer.pilot_labels) a.target.assign(control::kActionSize, 0.5f);
  std::int64_t stored = 0;
  auto fill = [&](std::int64_t n) {
    for (std::int64_t k = 0; k < n; ++k, ++stored) {
      for (float& x : o.vector) x = u(rng);
      for (float& x : o.image) x = u(rng);
      state.motion->store(o, a, u(rng), next, false, false);
      if (state.config && stored % 600 == 0) {
        for (float& x : co.image) x = u(rng);
        ca.discrete = static_cast<int>(stored / 600 % kCandidates);
        state.config->store(co, ca, u(rng), cnext, false, false, 300);
      }
    }
  };
  CheckpointCost cost;
  fill(transitions);
  Clock::time_point start = Clock::now();
  host.checkpoint();
  cost.first_s = std::chrono::duration<double>(Clock::now() - start).count();
  fill(new_transitions);
  start = Clock::now();
  host.checkpoint();
  cost.next_s = std::chrono::duration<double>(Clock::now() - start).count();
  return cost;
}

}  // namespace comorph::coopt
