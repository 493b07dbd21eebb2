// The motion level of the robot as an rl::Env, for learners tried on the
// robot without the hierarchy (rl::train, rl::evaluate, a learner's tests):
// a fixed chain in the config's training scenario, the motion mode of the
// ground truth (stair mode until the chain is on the top), the motion model's
// observation exactly as the trainer fills it (motion_spec, fill_motion) and
// R1 (Eq. 6) as the reward. An episode ends as MultiTaskEnv's does: success
// and failures are terminal, the step cap truncates.
#pragma once

#include <cstdint>
#include <string>

#include "coopt/config.hpp"
#include "rl/env.hpp"
#include "task/multitask_env.hpp"

namespace comorph::coopt {

class MotionEnv final : public rl::Env {
 public:
  // A chain of `modules` modules (kMinModules..kMaxModules; throws std::invalid_argument otherwise).
  MotionEnv(const CooptConfig& config, int modules);

  std::string name() const override { return "robot-chain" + std::to_string(modules_); }
  rl::ObservationSpec observation_spec() const override;
  rl::ActionSpec action_spec() const override;
  // The scene seed of the next episode; each reset() then moves on by one.
  // Stair heights take the config's three in turn (as an evaluation does).
  void seed(std::uint64_t seed) override;
  void reset(rl::Observation& observation) override;
  rl::StepResult step(const rl::Action& action, rl::Observation& next_observation) override;

  const task::MultiTaskEnv& env() const { return env_; }  // the episode's state (metrics, scripted pilots)

 private:
  CooptConfig config_;
  int modules_;
  task::MultiTaskEnv env_;
  std::uint64_t next_seed_ = 0;
  int episode_ = 0;
};

}  // namespace comorph::coopt
