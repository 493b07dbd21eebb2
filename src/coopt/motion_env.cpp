#include "coopt/motion_env.hpp"

#include <stdexcept>

#include "coopt/episode_runner.hpp"
#include "task/scenario.hpp"

namespace comorph::coopt {

MotionEnv::MotionEnv(const CooptConfig& config, int modules)
    : config_(config), modules_(modules), env_(config.env) {
  if (modules < kMinModules || modules > kMaxModules)
    throw std::invalid_argument("MotionEnv: modules must be " + std::to_string(kMinModules) + ".." +
                                std::to_string(kMaxModules) + ", got " + std::to_string(modules));
}

rl::ObservationSpec MotionEnv::observation_spec() const { return motion_spec(config_); }

rl::ActionSpec MotionEnv::action_spec() const { return {rl::ActionKind::kContinuous, control::kActionSize}; }

void MotionEnv::seed(std::uint64_t seed) {
  next_seed_ = seed;
  episode_ = 0;
}

void MotionEnv::reset(rl::Observation& o) {
  task::EpisodeSpec spec = eval_spec(config_, task::scenario_spec(config_.trainer.scenario), next_seed_++, episode_++);
  spec.configuration = make_chain(modules_);
  env_.reset(spec);
  fill_motion(env_.depth(), env_.state(), env_.clearance(), config_.trainer, o);
}

rl::StepResult MotionEnv::step(const rl::Action& action, rl::Observation& next) {
  const task::StepOutcome& r = env_.step(action.continuous.data(), env_.default_mode());
  fill_motion(env_.depth(), env_.state(), env_.clearance(), config_.trainer, next);
  return {static_cast<float>(r.reward), r.terminated, r.truncated};
}

}  // namespace comorph::coopt
