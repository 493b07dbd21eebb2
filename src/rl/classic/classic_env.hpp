// What the Gymnasium classic-control environments here (CartPole-v1,
// Pendulum-v1) share around their own dynamics: the parameters, a physical
// state that tests can read and set, the generator of initial states and the
// episode's step count with its time limit (Gymnasium's TimeLimit wrapper:
// truncated after max_episode_steps unless the step terminated). An
// environment gives its Definition: name, spaces and dynamics.
#pragma once

#include <cstdint>
#include <random>
#include <string>

#include "rl/env.hpp"

namespace comorph::rl {

template <class Params, class State>
class ClassicEnv : public Env {
 public:
  // What makes one classic environment differ from another. The dynamics are
  // plain functions of the parameters and the state.
  struct Definition {
    std::string name;
    ObservationSpec observation_spec;
    ActionSpec action_spec;
    State (*initial_state)(std::mt19937_64& rng);  // a random initial state
    // Applies `action` to `state`: the step's reward and `terminated`. Throws,
    // leaving `state` unchanged, on an action outside the action space.
    StepResult (*advance)(const Params& params, const Action& action, State& state);
    void (*observe)(const State& state, Observation& observation);
  };

  ClassicEnv(Definition definition, Params params) : definition_(std::move(definition)), params_(params) {}

  std::string name() const final { return definition_.name; }
  ObservationSpec observation_spec() const final { return definition_.observation_spec; }
  ActionSpec action_spec() const final { return definition_.action_spec; }
  void seed(std::uint64_t seed) final { rng_.seed(seed); }
  void reset(Observation& observation) final {
    state_ = definition_.initial_state(rng_);
    steps_ = 0;
    definition_.observe(state_, observation);
  }
  StepResult step(const Action& action, Observation& next_observation) final {
    StepResult result = definition_.advance(params_, action, state_);
    ++steps_;
    result.truncated = !result.terminated && steps_ >= params_.max_episode_steps;
    definition_.observe(state_, next_observation);
    return result;
  }

  const State& state() const { return state_; }
  void set_state(const State& state) { state_ = state; }

 private:
  Definition definition_;
  Params params_;
  State state_{};
  int steps_ = 0;  // steps since reset()
  std::mt19937_64 rng_{0};
};

}  // namespace comorph::rl
