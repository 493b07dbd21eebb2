// The acting side of a learner (Stable-Baselines3's policy / algorithm split):
// a copy of the networks that choose actions, the exploration schedule and the
// RNG it draws from. A loop that acts on one thread and learns on another
// holds a Policy on the acting thread and the Learner on the other; replay,
// optimizers and target networks then exist once, and the acting copy takes
// the learner's weights at each hand-over (sync_from).
//
//   auto policy = rl::make_policy("td3", args);    // rl/registry.hpp
//   policy->sync_from(learner);                    // the learner's acting weights
//   policy->act(obs, /*explore=*/true, action);
//   policy->count(terminated, truncated);          // the schedule's clock, as store() counts
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "rl/acting_state.hpp"
#include "rl/env.hpp"
#include "rl/learner.hpp"

namespace comorph::rl {

class Policy {
 public:
  virtual ~Policy() = default;
  // As Learner::act of the same algorithm, on this copy's weights, counters and RNG.
  virtual void act(const Observation& observation, bool explore, Action& action) = 0;
  // One acted transition, counted as Learner::store counts it: exploration
  // schedules (random-action warm-up, noise decay, epsilon) run on these counters.
  void count(bool terminated, bool truncated) {
    ++counters_.transitions;
    if (terminated || truncated) {
      ++counters_.episodes;
      acting_.start_episode();  // the next episode's exploration noise starts afresh
    }
  }
  // Copies the learner's acting networks (Learner::acting_networks) into this copy.
  void sync_from(const Learner& learner);
  // Moves this copy's networks towards the learner's: (1 - weight) mine +
  // weight its (a running mean of snapshots: weight 1 / k at the k-th).
  void blend_from(const Learner& learner, double weight);
  // The same from acting_weights()' buffer (an acting copy in another thread
  // or process is sent these bytes).
  void load_weights(const std::vector<float>& weights);
  // Networks, counters and RNG, in Learner::save_policy's format; load() also
  // reads a learner's full checkpoint (its networks, counters and RNG).
  void save(const std::string& path) const;
  void load(const std::string& path);
  const LearnerCounters& counters() const { return counters_; }
  // A trainer with several acting copies sets their schedule's clock to the
  // whole run's counts, and each episode's random stream (coopt's simulation threads).
  void set_counters(const LearnerCounters& counters) { counters_ = counters; }
  void reseed(std::uint64_t seed) {
    rng_.seed(seed);
    acting_.start_episode();
  }
  // The RNG as a value: an acting copy that continues another's random stream
  // (coopt's one-actor schedule) is handed it and hands it back.
  const std::mt19937_64& rng() const { return rng_; }
  void set_rng(const std::mt19937_64& rng) {
    rng_ = rng;
    acting_.start_episode();
  }

 protected:
  // `algorithm` and `networks_key` name the checkpoint's learner and the
  // archive entry of its acting networks; `device` is the config's.
  Policy(std::string algorithm, std::string networks_key, std::string device, std::uint64_t seed)
      : rng_(seed), algorithm_(std::move(algorithm)), key_(std::move(networks_key)), device_(std::move(device)) {}
  // The acting networks (a module holder: const access still loads into them).
  virtual torch::nn::Module& acting_module() const = 0;

  LearnerCounters counters_;
  std::mt19937_64 rng_;
  // The acting rule's noise state within an episode and its buffers.
  ActingState acting_;

 private:
  std::string algorithm_, key_, device_;
};

// The learner's acting networks' parameters, in their order, as one flat
// buffer (resized once: no allocation at later calls): what Policy::load_weights reads.
void acting_weights(const Learner& learner, std::vector<float>& weights);

// The policy of DQN, TD3 and SAC: a copy of the learner's acting network
// (Net: QNetwork, ActorCritic) and the algorithm's acting rule, the same
// function its learner acts with (so both draw the same numbers from their RNG).
template <class Net, class Config>
class NetworkPolicy final : public Policy {
 public:
  using Rule = void (*)(Net& net, const ObservationSpec& spec, int actions, const Config& config,
                        const torch::Device& device, const LearnerCounters& counters, std::mt19937_64& rng,
                        ActingState& state, const Observation& observation, bool explore, Action& action);
  // `actions`: action dimensions (continuous) or count (discrete).
  NetworkPolicy(std::string algorithm, std::string networks_key, const ObservationSpec& spec, int actions,
                const Config& config, std::uint64_t seed, Net net, Rule rule)
      : Policy(std::move(algorithm), std::move(networks_key), config.device, seed), spec_(spec), actions_(actions),
        config_(config), device_(config.device), net_(std::move(net)), rule_(rule) {}
  void act(const Observation& observation, bool explore, Action& action) override {
    rule_(net_, spec_, actions_, config_, device_, counters_, rng_, acting_, observation, explore, action);
  }

 protected:
  torch::nn::Module& acting_module() const override { return *net_.ptr(); }

 private:
  ObservationSpec spec_;
  int actions_;
  Config config_;
  torch::Device device_;
  Net net_;
  Rule rule_;
};

// The policy of a learner of this `seed` built alone: torch's generator is
// seeded as the learner's constructor seeds it, so its initial weights are the
// learner's (they are replaced by a sync anyway). `make` builds the acting
// network of the algorithm.
template <class Net, class Config>
std::unique_ptr<Policy> make_network_policy(std::string algorithm, std::string networks_key,
                                            const ObservationSpec& spec, int actions, const Config& config,
                                            std::uint64_t seed,
                                            Net (*make)(const ObservationSpec&, int, const Config&),
                                            typename NetworkPolicy<Net, Config>::Rule rule) {
  torch::manual_seed(seed);
  return std::make_unique<NetworkPolicy<Net, Config>>(std::move(algorithm), std::move(networks_key), spec, actions,
                                                      config, seed, make(spec, actions, config), rule);
}

}  // namespace comorph::rl
