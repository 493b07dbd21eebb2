// n-step returns (Sutton & Barto, ch. 7.1) from one actor's stream of
// transitions, made where the actor acts, before the hand-over: transition t
// leaves as (s_t, a_t, r_t + g r_{t+1} + ... + g^(m-1) r_{t+m-1}, s_{t+m}, m)
// with m = n, or fewer at the episode's end, and the learner's store() then
// discounts its bootstrap by g^m. The return is the behaviour's, uncorrected
// (as in Rainbow and Ape-X): with temporally correlated exploration it tells
// the critic what holding an action for m steps did, which one step's reward
// cannot. n = 1 passes every transition through unchanged.
//
//   rl::NStepReturns n_step(n, gamma);
//   n_step.add(obs, action, reward, next, terminated, truncated,
//              [&](const Observation& o, const Action& a, float r, const Observation& n,
//                  bool term, bool trunc, int steps) { learner.store(o, a, r, n, term, trunc, steps); });
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include "rl/env.hpp"

namespace comorph::rl {

class NStepReturns {
 public:
  NStepReturns(int n, double gamma) : n_(n), gamma_(gamma), pending_(static_cast<std::size_t>(n > 1 ? n : 0)) {
    if (n < 1) throw std::invalid_argument("NStepReturns: n must be at least 1, got " + std::to_string(n));
  }
  int n() const { return n_; }
  // The steps added and not yet emitted (an episode's end emits them all).
  int pending() const { return count_; }

  // Adds the next transition of the episode; `emit` receives each one that is
  // complete, oldest first: the one n - 1 steps back, or at the episode's end
  // (terminated or truncated) every one left, each ending in `next`.
  // Storage is reused: no allocation once every slot has been filled.
  template <class Emit>
  void add(const Observation& observation, const Action& action, float reward, const Observation& next,
           bool terminated, bool truncated, Emit&& emit) {
    if (n_ == 1) {
      emit(observation, action, reward, next, terminated, truncated, 1);
      return;
    }
    Pending& p = pending_[static_cast<std::size_t>((first_ + count_) % n_)];
    p.observation.image = observation.image;
    p.observation.vector = observation.vector;
    p.observation.valid_actions = observation.valid_actions;
    p.action.discrete = action.discrete;
    p.action.continuous = action.continuous;
    p.action.target = action.target;
    p.reward = reward;
    ++count_;
    if (terminated || truncated) {
      while (count_ > 0) emit_first(next, terminated, truncated, emit);
    } else if (count_ == n_) {
      emit_first(next, false, false, emit);
    }
  }

 private:
  struct Pending {
    Observation observation;
    Action action;
    float reward = 0;
  };
  template <class Emit>
  void emit_first(const Observation& next, bool terminated, bool truncated, Emit& emit) {
    // Summed in float, as one reward is stored, oldest first.
    float ret = 0, discount = 1;
    for (int i = 0; i < count_; ++i) {
      ret += discount * pending_[static_cast<std::size_t>((first_ + i) % n_)].reward;
      discount *= static_cast<float>(gamma_);
    }
    const Pending& p = pending_[static_cast<std::size_t>(first_)];
    emit(p.observation, p.action, ret, next, terminated, truncated, count_);
    first_ = (first_ + 1) % n_;
    --count_;
  }

  int n_;
  double gamma_;
  std::vector<Pending> pending_;  // a ring of n: pending_[(first_ + i) % n], i < count_
  int first_ = 0, count_ = 0;
};

}  // namespace comorph::rl
