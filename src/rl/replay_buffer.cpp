#include "rl/replay_buffer.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace comorph::rl {

ReplayBuffer::ReplayBuffer(ObservationSpec observation, ActionSpec action, std::int64_t capacity,
                           ImageStorage image_storage)
    : obs_spec_(observation), action_spec_(action), capacity_(capacity), image_storage_(image_storage) {
  if (capacity <= 0) throw std::invalid_argument("ReplayBuffer: capacity must be > 0");
  if (!observation.has_image() && !observation.has_vector())
    throw std::invalid_argument("ReplayBuffer: observation has neither image nor vector");
  const auto f32 = torch::TensorOptions().dtype(torch::kFloat32);
  if (observation.has_image()) {
    const auto dtype = image_storage == ImageStorage::kUint8 ? torch::kUInt8 : torch::kFloat16;
    const std::vector<std::int64_t> shape{capacity, observation.image_channels,
                                          observation.image_height, observation.image_width};
    image_ = torch::zeros(shape, torch::TensorOptions().dtype(dtype));
    next_image_ = torch::zeros(shape, torch::TensorOptions().dtype(dtype));
  }
  if (observation.has_vector()) {
    vector_ = torch::zeros({capacity, observation.vector_size}, f32);
    next_vector_ = torch::zeros({capacity, observation.vector_size}, f32);
  }
  if (action.kind == ActionKind::kDiscrete) {
    action_ = torch::zeros({capacity}, torch::TensorOptions().dtype(torch::kInt64));
    next_valid_ = torch::ones({capacity, action.size}, torch::TensorOptions().dtype(torch::kBool));
  } else {
    action_ = torch::zeros({capacity, action.size}, f32);
  }
  reward_ = torch::zeros({capacity}, f32);
  discount_ = torch::zeros({capacity}, f32);
  terminated_ = torch::zeros({capacity}, f32);
  if (action.kind == ActionKind::kContinuous) target_ = torch::zeros({capacity, action.size}, f32);
  has_target_ = torch::zeros({capacity}, f32);
}

void ReplayBuffer::store_image(const std::vector<float>& image, torch::Tensor& storage,
                               std::int64_t slot) {
  const int n = obs_spec_.image_size();
  if (static_cast<int>(image.size()) != n)
    throw std::invalid_argument("ReplayBuffer::add: image has " + std::to_string(image.size()) +
                                " values, expected " + std::to_string(n));
  if (image_storage_ == ImageStorage::kUint8) {
    std::uint8_t* dst = storage.data_ptr<std::uint8_t>() + slot * n;
    for (int i = 0; i < n; ++i)
      dst[i] = static_cast<std::uint8_t>(std::lround(std::clamp(image[i], 0.0f, 1.0f) * 255.0f));
  } else {
    at::Half* dst = storage.data_ptr<at::Half>() + slot * n;
    for (int i = 0; i < n; ++i) dst[i] = at::Half(image[i]);
  }
}

void ReplayBuffer::add(const Observation& obs, const Action& action, float reward,
                       const Observation& next, bool terminated, float discount) {
  const std::int64_t slot = position_;
  if (obs_spec_.has_image()) {
    store_image(obs.image, image_, slot);
    store_image(next.image, next_image_, slot);
  }
  if (obs_spec_.has_vector()) {
    const int v = obs_spec_.vector_size;
    if (static_cast<int>(obs.vector.size()) != v || static_cast<int>(next.vector.size()) != v)
      throw std::invalid_argument("ReplayBuffer::add: vector observation must have " +
                                  std::to_string(v) + " values");
    std::copy(obs.vector.begin(), obs.vector.end(), vector_.data_ptr<float>() + slot * v);
    std::copy(next.vector.begin(), next.vector.end(), next_vector_.data_ptr<float>() + slot * v);
  }
  if (action_spec_.kind == ActionKind::kDiscrete) {
    if (action.discrete < 0 || action.discrete >= action_spec_.size)
      throw std::invalid_argument("ReplayBuffer::add: discrete action " +
                                  std::to_string(action.discrete) + " outside [0, " +
                                  std::to_string(action_spec_.size) + ")");
    action_.data_ptr<std::int64_t>()[slot] = action.discrete;
    bool* mask = next_valid_.data_ptr<bool>() + slot * action_spec_.size;
    if (next.valid_actions.empty()) {
      std::fill(mask, mask + action_spec_.size, true);
    } else {
      if (static_cast<int>(next.valid_actions.size()) != action_spec_.size)
        throw std::invalid_argument("ReplayBuffer::add: valid_actions must have " +
                                    std::to_string(action_spec_.size) + " entries");
      for (int i = 0; i < action_spec_.size; ++i) mask[i] = next.valid_actions[i] != 0;
    }
  } else {
    if (static_cast<int>(action.continuous.size()) != action_spec_.size)
      throw std::invalid_argument("ReplayBuffer::add: continuous action must have " +
                                  std::to_string(action_spec_.size) + " values");
    std::copy(action.continuous.begin(), action.continuous.end(),
              action_.data_ptr<float>() + slot * action_spec_.size);
  }
  reward_.data_ptr<float>()[slot] = reward;
  discount_.data_ptr<float>()[slot] = discount;
  terminated_.data_ptr<float>()[slot] = terminated ? 1.0f : 0.0f;
  if (!action.target.empty()) {
    if (!target_.defined() || static_cast<int>(action.target.size()) != action_spec_.size)
      throw std::invalid_argument("ReplayBuffer::add: a target needs a continuous action of the same size");
    std::copy(action.target.begin(), action.target.end(), target_.data_ptr<float>() + slot * action_spec_.size);
  } else if (target_.defined()) {
    std::fill_n(target_.data_ptr<float>() + slot * action_spec_.size, action_spec_.size, 0.0f);
  }
  has_target_.data_ptr<float>()[slot] = action.target.empty() ? 0.0f : 1.0f;
  position_ = (position_ + 1) % capacity_;
  size_ = std::min(size_ + 1, capacity_);
  ++added_;
}

torch::Tensor ReplayBuffer::images_as_float(const torch::Tensor& storage,
                                            const torch::Tensor& slots) const {
  torch::Tensor x = storage.index_select(0, slots).to(torch::kFloat32);
  if (image_storage_ == ImageStorage::kUint8) x.div_(255.0f);
  return x;
}

ReplayBatch ReplayBuffer::gather(const torch::Tensor& slots, const torch::Device& device) const {
  ReplayBatch b;
  if (obs_spec_.has_image()) {
    b.image = images_as_float(image_, slots).to(device);
    b.next_image = images_as_float(next_image_, slots).to(device);
  }
  if (obs_spec_.has_vector()) {
    b.vector = vector_.index_select(0, slots).to(device);
    b.next_vector = next_vector_.index_select(0, slots).to(device);
  }
  b.action = action_.index_select(0, slots).to(device);
  b.reward = reward_.index_select(0, slots).to(device);
  b.bootstrap = (discount_.index_select(0, slots) * (1.0f - terminated_.index_select(0, slots)))
                    .to(device);
  if (next_valid_.defined()) b.next_valid_actions = next_valid_.index_select(0, slots).to(device);
  if (target_.defined()) b.target = target_.index_select(0, slots).to(device);
  b.has_target = has_target_.index_select(0, slots).to(device);
  return b;
}

namespace {

// Slots drawn uniformly with replacement from the first `size`.
void draw_slots(torch::Tensor& slots, std::int64_t size, std::mt19937_64& rng) {
  if (size == 0) throw std::logic_error("ReplayBuffer::sample: buffer is empty");
  std::int64_t* s = slots.data_ptr<std::int64_t>();
  std::uniform_int_distribution<std::int64_t> pick(0, size - 1);
  for (std::int64_t i = 0; i < slots.numel(); ++i) s[i] = pick(rng);
}

// Rows `slots` of a contiguous storage tensor into the first `count` rows of `into`.
void copy_rows(const torch::Tensor& storage, const std::int64_t* slots, std::int64_t count, torch::Tensor& into) {
  const std::size_t row = static_cast<std::size_t>(storage.stride(0) * storage.element_size());
  const char* from = static_cast<const char*>(storage.data_ptr());
  char* to = static_cast<char*>(into.data_ptr());
  for (std::int64_t i = 0; i < count; ++i) std::memcpy(to + i * row, from + slots[i] * row, row);
}

}  // namespace

ReplayBatch ReplayBuffer::sample(std::int64_t batch_size, std::mt19937_64& rng,
                                 const torch::Device& device) const {
  torch::Tensor slots = torch::empty({batch_size}, torch::TensorOptions().dtype(torch::kInt64));
  draw_slots(slots, size_, rng);
  return gather(slots, device);
}

void ReplayBuffer::sample_into(ReplayBatch& b, std::int64_t batch_size, std::mt19937_64& rng,
                               const torch::Device& device) const {
  if (obs_spec_.has_image() || !device.is_cpu()) {
    b = sample(batch_size, rng, device);
    return;
  }
  if (!b.slots.defined() || b.slots.size(0) != batch_size) {
    b = ReplayBatch{};
    b.slots = torch::empty({batch_size}, torch::TensorOptions().dtype(torch::kInt64));
    const auto like = [&](const torch::Tensor& storage) {
      std::vector<std::int64_t> shape = storage.sizes().vec();
      shape[0] = batch_size;
      return torch::empty(shape, storage.options());
    };
    b.vector = like(vector_);
    b.next_vector = like(next_vector_);
    b.action = like(action_);
    b.reward = like(reward_);
    b.bootstrap = like(discount_);
    if (next_valid_.defined()) b.next_valid_actions = like(next_valid_);
    if (target_.defined()) b.target = like(target_);
    b.has_target = like(has_target_);
  }
  draw_slots(b.slots, size_, rng);
  // Row copies in plain loops: a dozen LibTorch operations per update cost
  // more in dispatch than their copying at these sizes. The same values as gather().
  const std::int64_t* slots = b.slots.data_ptr<std::int64_t>();
  copy_rows(vector_, slots, batch_size, b.vector);
  copy_rows(next_vector_, slots, batch_size, b.next_vector);
  copy_rows(action_, slots, batch_size, b.action);
  copy_rows(reward_, slots, batch_size, b.reward);
  const float* discount = discount_.data_ptr<float>();
  const float* terminated = terminated_.data_ptr<float>();
  float* bootstrap = b.bootstrap.data_ptr<float>();
  for (std::int64_t i = 0; i < batch_size; ++i) bootstrap[i] = discount[slots[i]] * (1.0f - terminated[slots[i]]);
  if (next_valid_.defined()) copy_rows(next_valid_, slots, batch_size, b.next_valid_actions);
  if (target_.defined()) copy_rows(target_, slots, batch_size, b.target);
  copy_rows(has_target_, slots, batch_size, b.has_target);
}

void ReplayBuffer::save(torch::serialize::OutputArchive& a) const {
  // Only the filled slots are written (a fresh buffer of the same capacity
  // is rebuilt on load).
  const std::int64_t n = size_;
  auto filled = [n](const torch::Tensor& t) { return t.slice(0, 0, n).clone(); };
  a.write("capacity", torch::tensor({capacity_}));
  a.write("size", torch::tensor({size_}));
  a.write("position", torch::tensor({position_}));
  a.write("added", torch::tensor({added_}));
  a.write("image_storage", torch::tensor({static_cast<std::int64_t>(image_storage_)}));
  if (image_.defined()) {
    a.write("image", filled(image_));
    a.write("next_image", filled(next_image_));
  }
  if (vector_.defined()) {
    a.write("vector", filled(vector_));
    a.write("next_vector", filled(next_vector_));
  }
  a.write("action", filled(action_));
  a.write("reward", filled(reward_));
  a.write("discount", filled(discount_));
  a.write("terminated", filled(terminated_));
  if (target_.defined()) a.write("target", filled(target_));
  a.write("has_target", filled(has_target_));
  if (next_valid_.defined()) a.write("next_valid", filled(next_valid_));
}

void ReplayBuffer::load(torch::serialize::InputArchive& a) {
  torch::Tensor t;
  a.read("capacity", t);
  if (t.item<std::int64_t>() != capacity_)
    throw std::runtime_error("ReplayBuffer::load: saved capacity " +
                             std::to_string(t.item<std::int64_t>()) + " != this buffer's " +
                             std::to_string(capacity_));
  a.read("image_storage", t);
  if (t.item<std::int64_t>() != static_cast<std::int64_t>(image_storage_))
    throw std::runtime_error("ReplayBuffer::load: saved image storage type differs");
  a.read("size", t);
  size_ = t.item<std::int64_t>();
  a.read("position", t);
  position_ = t.item<std::int64_t>();
  // Buffers saved before `added` was kept: a count with the same slots.
  if (a.try_read("added", t))
    added_ = t.item<std::int64_t>();
  else
    added_ = size_ < capacity_ ? size_ : capacity_ + position_;
  auto restore = [&](const char* key, torch::Tensor& dst) {
    torch::Tensor src;
    a.read(key, src);
    if (src.size(0) != size_ || src.sizes().slice(1) != dst.sizes().slice(1) ||
        src.scalar_type() != dst.scalar_type())
      throw std::runtime_error(std::string("ReplayBuffer::load: field \"") + key +
                               "\" has the wrong shape or type for this buffer");
    dst.slice(0, 0, size_).copy_(src);
  };
  if (image_.defined()) {
    restore("image", image_);
    restore("next_image", next_image_);
  }
  if (vector_.defined()) {
    restore("vector", vector_);
    restore("next_vector", next_vector_);
  }
  restore("action", action_);
  restore("reward", reward_);
  restore("discount", discount_);
  restore("terminated", terminated_);
  restore("has_target", has_target_);
  if (target_.defined()) restore("target", target_);
  if (next_valid_.defined()) restore("next_valid", next_valid_);
}

std::vector<std::pair<std::string, torch::Tensor>> ReplayBuffer::fields() const {
  std::vector<std::pair<std::string, torch::Tensor>> f;
  for (const auto& [key, t] : {std::pair<const char*, const torch::Tensor*>{"image", &image_},
                               {"next_image", &next_image_}, {"vector", &vector_}, {"next_vector", &next_vector_},
                               {"action", &action_}, {"reward", &reward_}, {"discount", &discount_},
                               {"terminated", &terminated_}, {"next_valid", &next_valid_}, {"target", &target_},
                               {"has_target", &has_target_}})
    if (t->defined()) f.emplace_back(key, *t);
  return f;
}

namespace {
// The slots of `count` transitions from global index `first`: at most two
// contiguous runs (the ring wraps once). fn(slot, offset in the run of transitions, length).
template <class F>
void for_slot_runs(std::int64_t first, std::int64_t count, std::int64_t capacity, F fn) {
  std::int64_t offset = 0;
  while (offset < count) {
    const std::int64_t slot = (first + offset) % capacity;
    const std::int64_t length = std::min(count - offset, capacity - slot);
    fn(slot, offset, length);
    offset += length;
  }
}
}  // namespace

void ReplayBuffer::save_segment(torch::serialize::OutputArchive& a, std::int64_t first, std::int64_t count) const {
  if (count < 0 || first < added_ - size_ || first + count > added_)
    throw std::logic_error("ReplayBuffer::save_segment: transitions [" + std::to_string(first) + ", " +
                           std::to_string(first + count) + ") are not all held (held: [" +
                           std::to_string(added_ - size_) + ", " + std::to_string(added_) + "))");
  a.write("first", torch::tensor({first}));
  a.write("count", torch::tensor({count}));
  a.write("image_storage", torch::tensor({static_cast<std::int64_t>(image_storage_)}));
  for (const auto& [key, storage] : fields()) {
    std::vector<torch::Tensor> runs;
    for_slot_runs(first, count, capacity_, [&](std::int64_t slot, std::int64_t, std::int64_t length) {
      runs.push_back(storage.slice(0, slot, slot + length));
    });
    a.write(key, runs.empty() ? storage.slice(0, 0, 0).clone() : torch::cat(runs));
  }
}

void ReplayBuffer::begin_segments(std::int64_t added) {
  if (added < 0) throw std::runtime_error("ReplayBuffer: a negative transition count " + std::to_string(added));
  added_ = added;
  size_ = std::min(added, capacity_);
  position_ = added % capacity_;
}

void ReplayBuffer::load_segment(torch::serialize::InputArchive& a, std::int64_t first, std::int64_t count) {
  torch::Tensor t;
  a.read("first", t);
  const std::int64_t saved_first = t.item<std::int64_t>();
  a.read("count", t);
  const std::int64_t saved_count = t.item<std::int64_t>();
  if (saved_first != first || saved_count != count)
    throw std::runtime_error("replay segment holds transitions [" + std::to_string(saved_first) + ", " +
                             std::to_string(saved_first + saved_count) + "), its index says [" +
                             std::to_string(first) + ", " + std::to_string(first + count) + ")");
  a.read("image_storage", t);
  if (t.item<std::int64_t>() != static_cast<std::int64_t>(image_storage_))
    throw std::runtime_error("replay segment: saved image storage type differs");
  // Only the part that is still held: the last size_ transitions.
  const std::int64_t from = std::max(first, added_ - size_);
  const std::int64_t to = std::min(first + count, added_);
  for (const auto& [key, storage] : fields()) {
    torch::Tensor src;
    a.read(key, src);
    if (src.size(0) != count || src.sizes().slice(1) != storage.sizes().slice(1) ||
        src.scalar_type() != storage.scalar_type())
      throw std::runtime_error("replay segment: field \"" + key + "\" has the wrong shape or type for this buffer");
    if (to <= from) continue;
    for_slot_runs(from, to - from, capacity_, [&](std::int64_t slot, std::int64_t offset, std::int64_t length) {
      const std::int64_t at = from - first + offset;
      storage.slice(0, slot, slot + length).copy_(src.slice(0, at, at + length));
    });
  }
}

void ReplayBuffer::save(const std::string& path) const {
  torch::serialize::OutputArchive a;
  save(a);
  a.save_to(path);
}

void ReplayBuffer::load(const std::string& path) {
  torch::serialize::InputArchive a;
  a.load_from(path);
  load(a);
}

}  // namespace comorph::rl
