// One task::MultiTaskEnv with Gymnasium's episode rules, shared by the single
// and the batched env of comorph._core: seeding (reset(seed) starts episode
// `seed` and seeds the stream the following unseeded resets draw their
// episode seeds from), step before reset / after the end refused, checked
// options. No Python here: the batched env calls it from its threads.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>

#include "task/env_config.hpp"
#include "task/multitask_env.hpp"

namespace comorph::python {

struct EnvOptions {
  task::EnvConfig config;
  std::shared_ptr<sim::ModelCache> cache;  // null: the env compiles its own models
  int modules = 4;                         // chain length of an episode without the `modules` option
  int obstacles = -1;                      // K; -1: SceneParams::obstacles
  sim::Variant variant = sim::Variant::standard;
};

class EnvCore {
 public:
  explicit EnvCore(const EnvOptions& o) : options_(o), env_(o.config, o.cache) {}

  static void check_modules(int modules, const char* what) {
    if (modules < kMinModules || modules > kMaxModules)
      throw std::invalid_argument(std::string(what) + " must be in " + std::to_string(kMinModules) + ".." +
                                  std::to_string(kMaxModules) + ", got " + std::to_string(modules));
  }

  // modules <= 0: the default chain; stair_height <= 0: drawn from the seed.
  void reset(std::optional<std::uint64_t> seed, int modules, double stair_height) {
    if (modules != 0) check_modules(modules, "modules");
    if (!(stair_height >= 0.0 && stair_height <= 0.3))
      throw std::invalid_argument("stair_height must be in [0, 0.3] m (0 = drawn from the seed), got " +
                                  std::to_string(stair_height));
    if (seed) {
      if (*seed > kMaxSeed)
        throw std::invalid_argument("seed must be in 0..2^53, got " + std::to_string(*seed));
      rng_.seed(*seed);
      episode_seed_ = *seed;
    } else {
      if (!seeded_) rng_.seed(std::random_device{}());
      episode_seed_ = rng_() >> 11;  // 53 bits
    }
    seeded_ = true;
    task::EpisodeSpec spec;
    spec.seed = episode_seed_;
    spec.configuration = make_chain(modules > 0 ? modules : options_.modules);
    spec.stair_height = stair_height;
    spec.obstacles = options_.obstacles;
    spec.variant = options_.variant;
    env_.reset(spec);
    started_ = true;
  }

  const task::StepOutcome& step(const float* action) {
    require_started("step");
    if (env_.done())
      throw std::runtime_error(std::string("step after the episode ended (") +
                               task::termination_name(env_.last().reason) + "); call reset()");
    return env_.step(action);  // motion mode: the ground truth (stairs, then flat)
  }

  void reconfigure(int modules) {
    require_started("reconfigure");
    if (env_.done()) throw std::runtime_error("reconfigure after the episode ended; call reset()");
    if (modules < kMinModules || modules >= env_.modules())
      throw std::invalid_argument("reconfigure sheds tail modules: modules must be in " + std::to_string(kMinModules) +
                                  ".." + std::to_string(env_.modules() - 1) + ", got " + std::to_string(modules));
    env_.reconfigure(make_chain(modules));
  }

  void require_started(const char* what) const {
    if (!started_) throw std::runtime_error(std::string(what) + " before reset(); call reset() first");
  }
  bool started() const { return started_; }
  std::uint64_t episode_seed() const { return episode_seed_; }
  const task::MultiTaskEnv& env() const { return env_; }
  task::MultiTaskEnv& mutable_env() { return env_; }

 private:
  static constexpr std::uint64_t kMaxSeed = std::uint64_t(1) << 53;
  EnvOptions options_;
  task::MultiTaskEnv env_;
  std::mt19937_64 rng_;
  std::uint64_t episode_seed_ = 0;
  bool seeded_ = false, started_ = false;
};

}  // namespace comorph::python
