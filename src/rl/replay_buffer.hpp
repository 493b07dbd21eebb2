// Uniform experience replay with storage preallocated at construction.
//
// Images are stored compactly (uint8, value * 255 rounded, or float16) and
// converted back to float32 in [0, 1] when a batch is sampled; vectors,
// actions and rewards are float32 (discrete actions int64). Every transition
// carries its own discount (gamma^k for a semi-MDP segment of k steps) and its
// `terminated` flag; the sampled `bootstrap` = discount * (1 - terminated) is
// what multiplies the next state's value, so a truncated transition (not
// terminated) still bootstraps. For discrete actions the valid-action mask of
// the next state is stored too (the DQN target maximises over it).
//
// Storage lives on the CPU; sampled batches are moved to `device`.
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "rl/env.hpp"
#include "rl/learner_params.hpp"  // ImageStorage

namespace comorph::rl {

struct ReplayBatch {
  torch::Tensor image, next_image;           // [B, C, H, W] float32, or undefined
  torch::Tensor vector, next_vector;         // [B, V] float32, or undefined
  torch::Tensor action;                      // [B, A] float32, or [B] int64 (discrete)
  torch::Tensor reward;                      // [B] float32
  torch::Tensor bootstrap;                   // [B] float32: discount, 0 when terminated
  torch::Tensor next_valid_actions;          // [B, n] bool (discrete), or undefined
  torch::Tensor target;                      // [B, A] float32: the demonstrator's action (continuous), 0 where none
  torch::Tensor has_target;                  // [B] float32: 1 where the transition has a target
  torch::Tensor slots;                       // [B] int64: the slots they came from (sample_into)
};

class ReplayBuffer {
 public:
  ReplayBuffer(ObservationSpec observation, ActionSpec action, std::int64_t capacity,
               ImageStorage image_storage = ImageStorage::kUint8);

  // Copies one transition into the next slot (overwrites the oldest once full).
  // `discount` is gamma^k of this transition.
  void add(const Observation& observation, const Action& action, float reward,
           const Observation& next_observation, bool terminated, float discount);

  // `batch_size` transitions drawn uniformly with replacement by `rng`.
  ReplayBatch sample(std::int64_t batch_size, std::mt19937_64& rng,
                     const torch::Device& device) const;
  // As sample(), into `batch`, whose tensors are allocated at the first call
  // and reused after (no allocation, no LibTorch operation). For a vector
  // observation on the CPU; otherwise it assigns sample()'s batch.
  // The same draws from `rng`, the same values.
  void sample_into(ReplayBatch& batch, std::int64_t batch_size, std::mt19937_64& rng,
                   const torch::Device& device) const;
  // The transitions at the given slots (tests, debugging).
  ReplayBatch gather(const torch::Tensor& slots, const torch::Device& device) const;

  std::int64_t size() const { return size_; }
  std::int64_t capacity() const { return capacity_; }
  std::int64_t next_slot() const { return position_; }
  // Transitions ever added = the global index of the next one. Transition g
  // is in slot g % capacity while it is among the last size() (g >= added() - size()).
  std::int64_t added() const { return added_; }
  const ObservationSpec& observation_spec() const { return obs_spec_; }

  void save(torch::serialize::OutputArchive& archive) const;
  void load(torch::serialize::InputArchive& archive);
  void save(const std::string& path) const;
  void load(const std::string& path);

  // Segments (rl/replay_segments.hpp: a checkpoint writes only what is new).
  // save_segment: transitions [first, first + count) by global index, which
  // must all still be held. To read segments back, begin_segments(added) sets
  // the counts of a buffer that has had `added` transitions, then each
  // load_segment(first, count) puts those of its transitions that are still
  // held (the last min(added, capacity)) into their slots.
  void save_segment(torch::serialize::OutputArchive& archive, std::int64_t first, std::int64_t count) const;
  void begin_segments(std::int64_t added);
  void load_segment(torch::serialize::InputArchive& archive, std::int64_t first, std::int64_t count);

 private:
  void store_image(const std::vector<float>& image, torch::Tensor& storage, std::int64_t slot);
  // Every storage tensor with its archive key (those this buffer has).
  std::vector<std::pair<std::string, torch::Tensor>> fields() const;
  torch::Tensor images_as_float(const torch::Tensor& storage, const torch::Tensor& slots) const;

  ObservationSpec obs_spec_;
  ActionSpec action_spec_;
  std::int64_t capacity_;
  ImageStorage image_storage_;
  std::int64_t size_ = 0;
  std::int64_t position_ = 0;
  std::int64_t added_ = 0;

  torch::Tensor image_, next_image_, vector_, next_vector_;
  torch::Tensor action_, reward_, discount_, terminated_, next_valid_, target_, has_target_;
};

}  // namespace comorph::rl
