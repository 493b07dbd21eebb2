// What every learner (DQN, TD3, SAC) offers to an outside training loop, and
// the small pieces they share: counters, RNG, schedules, YAML reading,
// checkpoint files, device and thread settings.
//
// Step-by-step use by a caller that owns the loop (the hierarchical trainer):
//   learner.act(obs, /*explore=*/true, action);      // InferenceMode inside
//   ... env step ...
//   learner.store(obs, action, reward, next_obs, terminated, truncated, k);
//   for (int i = learner.updates_due(); i > 0; --i) learner.update();  // or when it wants
// A transition may stand for k environment steps (a semi-MDP segment): it is
// then discounted by gamma^k.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/torch_archive.hpp"  // save_archive: every save()
#include "rl/env.hpp"
#include "rl/learner_params.hpp"

namespace torch::nn {
class Module;
}  // namespace torch::nn
namespace torch::serialize {
class OutputArchive;
class InputArchive;
}  // namespace torch::serialize

namespace comorph::rl {

class ReplayBuffer;  // rl/replay_buffer.hpp

// Counters every learner keeps; all are part of a checkpoint.
struct LearnerCounters {
  std::int64_t transitions = 0;  // store() calls
  std::int64_t episodes = 0;     // stored transitions that ended an episode
  std::int64_t updates = 0;      // gradient steps done by update()
};

class Learner {
 public:
  virtual ~Learner() = default;
  // Chooses an action for one observation. explore=false is the greedy policy.
  virtual void act(const Observation& observation, bool explore, Action& action) = 0;
  // Records one transition; `steps` environment steps were taken (discount gamma^steps).
  virtual void store(const Observation& observation, const Action& action, float reward,
                     const Observation& next_observation, bool terminated, bool truncated,
                     int steps = 1) = 0;
  // Gradient steps the configuration asks for after the latest store()
  // (train_frequency / gradient_steps / learning_starts); 0 most of the time.
  virtual int updates_due() const = 0;
  // One gradient step on a batch sampled from the replay buffer.
  virtual void update() = 0;
  // Everything needed to continue exactly: networks, targets, optimizers,
  // replay buffer, counters, RNG state.
  virtual void save(const std::string& path) const = 0;
  virtual void load(const std::string& path) = 0;
  // The networks alone (no target networks, optimizers or replay): what a
  // trained policy ships as. load() reads either kind; after a policy-only
  // file the learner acts as the saved one did (greedy), and everything else
  // stays as constructed, so it cannot continue training exactly.
  virtual void save_policy(const std::string& path) const = 0;
  // The acting networks alone from a policy file or a full checkpoint (what
  // Policy::load reads); counters, RNG, optimizers and replay stay as they
  // are. Another run's trained model as a starting point (coopt's
  // trainer.refit_motion_from). Learners that cannot say so throw.
  virtual void load_acting_networks(const std::string& path) {
    throw std::logic_error("this learner cannot load acting networks alone (" + path + ")");
  }
  // The replay buffer, and save() without it: the hierarchical trainer writes
  // the buffer apart, as segments (rl/replay_segments.hpp). load() of such a
  // file leaves replay() as it is.
  virtual ReplayBuffer& replay() = 0;
  virtual void save_without_replay(const std::string& path) const = 0;
  virtual const LearnerCounters& counters() const = 0;
  // The networks act() uses (what save_policy writes): a Policy
  // (rl/policy.hpp) copies them in Policy::sync_from.
  virtual const torch::nn::Module& acting_networks() const = 0;
  // Loss of the latest update() (critic / Q loss), for logs.
  virtual double last_loss() const = 0;
  // The RNG that act() and update() draw from, as a value: an acting copy
  // (rl::Policy) that continues this stream is handed it and hands it back
  // (coopt's one-actor schedule). Learners that cannot say so throw.
  virtual const std::mt19937_64& rng() const { throw std::logic_error("this learner has no RNG to hand out"); }
  virtual void set_rng(const std::mt19937_64& /*rng*/) {
    throw std::logic_error("this learner has no RNG to take back");
  }
};

// Linear interpolation from `start` to `end` over `duration` units, then `end`.
struct LinearSchedule {
  double start = 1.0;
  double end = 1.0;
  double duration = 0.0;  // 0 = always `end`
  double at(double t) const {
    if (duration <= 0.0 || t >= duration) return end;
    return start + (end - start) * (t / duration);
  }
};

// Where the YAML presets are: configs/rl of resource_dir() (common/resources.hpp).
std::string rl_config_dir();

// Sets the intra-op and inter-op thread counts of torch. The inter-op count
// can only be set once per process; later calls leave it alone.
void set_torch_threads(int intra_op_threads, int inter_op_threads);

// RNG state as text (std::mt19937_64's stream format), for checkpoints.
std::string rng_state(const std::mt19937_64& rng);
void set_rng_state(std::mt19937_64& rng, const std::string& state);

// Shared checkpoint pieces.
void write_common(torch::serialize::OutputArchive& archive, const LearnerCounters& counters,
                  const std::mt19937_64& rng, const std::string& algorithm);
void read_common(torch::serialize::InputArchive& archive, LearnerCounters& counters,
                 std::mt19937_64& rng, const std::string& algorithm);
// save_policy's file: the common header, a policy-only mark and `networks`
// under `key`. read_policy_only loads `networks` from such an archive and
// returns true, or returns false (and reads nothing) for a full checkpoint.
void save_policy_file(const std::string& path, const torch::nn::Module& networks, const std::string& key,
                      const LearnerCounters& counters, const std::mt19937_64& rng, const std::string& algorithm);
bool read_policy_only(torch::serialize::InputArchive& archive, const std::string& key, torch::nn::Module& networks);
// A learner archive's replay: the buffer under "replay", or (with_replay
// false) a mark that it is written elsewhere; read_replay reads either.
void write_replay(torch::serialize::OutputArchive& archive, const ReplayBuffer& replay, bool with_replay);
void read_replay(torch::serialize::InputArchive& archive, ReplayBuffer& replay);

}  // namespace comorph::rl
