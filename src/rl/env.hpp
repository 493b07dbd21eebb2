// The interface between environments and learners (no torch, no MuJoCo).
//
// An observation is an optional image (C x H x W floats in [0, 1], row-major)
// plus an optional vector, plus, for discrete actions, the mask of the actions
// that are valid in this state. Continuous actions are always normalised to
// [-1, 1] per dimension: an environment scales them to its own units (this is
// what the robot's 5-D action already is, and it keeps the learners unit-free).
//
// Episode ends follow Gymnasium: `terminated` means the MDP reached a terminal
// state (no bootstrapping from the next state); `truncated` means the episode
// was cut for a reason outside the MDP (a step cap): the next state still has a
// value, and the learners bootstrap from it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace comorph::rl {

struct ObservationSpec {
  int image_channels = 0;  // 0 = no image
  int image_height = 0;    // pixels
  int image_width = 0;     // pixels
  int vector_size = 0;     // 0 = no vector
  // 0, or the vector's last head_selector values are a one-hot choice of one
  // of that many actor heads: TD3's actor then has one group of outputs per
  // head, and a row acts and learns through its chosen group only (the
  // hidden layers are shared). The selector is part of the vector, so both
  // networks see it as input too.
  int head_selector = 0;

  bool has_image() const { return image_channels > 0; }
  bool has_vector() const { return vector_size > 0; }
  int image_size() const { return image_channels * image_height * image_width; }
  int actor_heads() const { return head_selector > 0 ? head_selector : 1; }
  // The head a vector chooses: the position of the largest value of its
  // selector block (0 without one).
  int head_of(const float* vector) const {
    int head = 0;
    for (int k = 1; k < head_selector; ++k)
      if (vector[vector_size - head_selector + k] > vector[vector_size - head_selector + head]) head = k;
    return head;
  }
};

enum class ActionKind { kDiscrete, kContinuous };

struct ActionSpec {
  ActionKind kind = ActionKind::kContinuous;
  int size = 0;  // number of discrete actions, or number of continuous dimensions
};

struct Observation {
  std::vector<float> image;             // image_size() values in [0, 1], or empty
  std::vector<float> vector;            // vector_size values, or empty
  std::vector<std::uint8_t> valid_actions;  // discrete only: 1 = valid; empty = all valid
};

struct Action {
  int discrete = -1;              // index in [0, size) for discrete actions
  std::vector<float> continuous;  // size values in [-1, 1] for continuous actions
  // A demonstrator's action for the same state (a behaviour-cloning target,
  // continuous only), or empty when there is none.
  std::vector<float> target;
};

struct StepResult {
  float reward = 0.0f;
  bool terminated = false;  // terminal state of the MDP: do not bootstrap
  bool truncated = false;   // cut by a step cap: bootstrap from the next state
};

class Env {
 public:
  virtual ~Env() = default;
  virtual std::string name() const = 0;
  virtual ObservationSpec observation_spec() const = 0;
  virtual ActionSpec action_spec() const = 0;
  // Re-seeds the environment's own random generator (initial states).
  virtual void seed(std::uint64_t seed) = 0;
  // Starts an episode and writes its first observation into `observation`
  // (whose vectors are reused: no allocation once sized).
  virtual void reset(Observation& observation) = 0;
  // Applies `action` and writes the next observation.
  virtual StepResult step(const Action& action, Observation& next_observation) = 0;
};

// Sizes the buffers of an observation for `spec` (once, before a loop).
inline void allocate(const ObservationSpec& spec, Observation& observation) {
  observation.image.assign(static_cast<std::size_t>(spec.image_size()), 0.0f);
  observation.vector.assign(static_cast<std::size_t>(spec.vector_size), 0.0f);
}

}  // namespace comorph::rl
