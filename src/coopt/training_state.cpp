#include "coopt/training_state.hpp"

#include <torch/torch.h>

#include "coopt/segment.hpp"
#include "rl/registry.hpp"

namespace comorph::coopt {
namespace {

rl::LearnerArgs motion_args(const CooptConfig& c, std::uint64_t seed) {
  rl::LearnerArgs a;
  a.observation = motion_spec(c);
  a.action = {rl::ActionKind::kContinuous, control::kActionSize};
  a.seed = seed;
  if (c.trainer.motion_algo == "td3") a.config = c.td3;
  if (c.trainer.motion_algo == "sac") a.config = c.sac;
  if (const auto it = c.other_learners.find(c.trainer.motion_algo); it != c.other_learners.end()) a.config = it->second;
  a.random_action_episodes = c.trainer.warmup_episodes;  // the trainer's warm-up replaces the config's
  return a;
}

}  // namespace

std::unique_ptr<rl::Learner> make_motion_learner(const CooptConfig& c, std::uint64_t seed) {
  return rl::make_learner(c.trainer.motion_algo, motion_args(c, seed));
}

std::unique_ptr<rl::Policy> make_motion_policy(const CooptConfig& c, std::uint64_t seed) {
  return rl::make_policy(c.trainer.motion_algo, motion_args(c, seed));
}

namespace {
rl::LearnerArgs dqn_args(const CooptConfig& c, std::uint64_t seed, const rl::DqnConfig& params) {
  rl::LearnerArgs a;
  a.observation = config_spec(c);
  a.action = {rl::ActionKind::kDiscrete, kCandidates};
  a.seed = seed;
  a.config = params;
  return a;
}
std::unique_ptr<rl::Learner> make_dqn(const CooptConfig& c, std::uint64_t seed, const rl::DqnConfig& params) {
  if (c.trainer.mode != TrainerMode::hierarchical) return nullptr;
  return rl::make_learner("dqn", dqn_args(c, seed, params));
}
}  // namespace

std::unique_ptr<rl::Policy> make_config_policy(const CooptConfig& c, bool refit) {
  if (c.trainer.mode != TrainerMode::hierarchical) return nullptr;
  return rl::make_policy("dqn", dqn_args(c, 0, config_model_params(c, refit)));
}

const rl::DqnConfig& config_model_params(const CooptConfig& c, bool refit) { return refit ? c.dqn_refit : c.dqn; }

std::unique_ptr<rl::Learner> make_config_model(const CooptConfig& c, std::uint64_t seed) {
  return make_dqn(c, seed, c.dqn);
}

std::unique_ptr<rl::Learner> make_refit_config_model(const CooptConfig& c) {
  return make_dqn(c, static_cast<std::uint64_t>(c.trainer.seed) + 3, c.dqn_refit);
}

TrainingState::TrainingState(const CooptConfig& c)
    : rng(c.trainer.seed * 7919ULL + 17), curriculum(stair_heights(c), c.trainer.stair_curriculum_window),
      chain_curriculum(stair_heights(c), kMinModules, kMaxModules, c.trainer.chain_curriculum_window) {
  rl::set_torch_threads(c.trainer.torch_threads, 1);  // before the models: they run on these threads
  const std::uint64_t seed = static_cast<std::uint64_t>(c.trainer.seed);
  motion = make_motion_learner(c, seed);
  motion_on_policy = rl::learner_entry(c.trainer.motion_algo).on_policy;
  agent.motion = make_motion_policy(c, seed + 1);
  agent.motion->sync_from(*motion);
  config = make_config_model(c, seed + 2);
  agent.config = make_config_policy(c, false);
}

void TrainingState::start_refit(const CooptConfig& c) {
  config = make_refit_config_model(c);
  agent.config = make_config_policy(c, true);
  config_refit = true;
}

TrainingState::~TrainingState() = default;

}  // namespace comorph::coopt
