#include "rl/off_policy.hpp"

#include <torch/torch.h>

#include <cmath>
#include <stdexcept>

namespace comorph::rl {

torch::Tensor gaussian_noise(std::int64_t rows, std::int64_t cols, double std, std::mt19937_64& rng,
                             const torch::Device& device) {
  torch::Tensor noise = torch::empty({rows, cols}, torch::kFloat32);
  float* p = noise.data_ptr<float>();
  std::normal_distribution<float> normal(0.0f, static_cast<float>(std));
  for (std::int64_t i = 0; i < rows * cols; ++i) p[i] = normal(rng);
  return noise.to(device);
}

void gradient_step(FlatAdam& optimizer, const torch::Tensor& loss, double max_grad_norm) {
  optimizer.zero_grad();
  loss.backward();
  clip_and_step(optimizer, max_grad_norm);
}

void clip_and_step(FlatAdam& optimizer, double max_grad_norm) {
  if (max_grad_norm > 0) optimizer.clip_grad_norm(max_grad_norm);
  optimizer.step();
}

torch::Tensor twin_critic_step(ActorCritic& nets, FlatAdam& optimizer, const ReplayBatch& b,
                               const torch::Tensor& y, double max_grad_norm, double& loss) {
  const torch::Tensor f = nets->critic_features(b.image, b.vector);
  const torch::Tensor critic_loss = torch::mse_loss(nets->q1(f, b.action), y) + torch::mse_loss(nets->q2(f, b.action), y);
  gradient_step(optimizer, critic_loss, max_grad_norm);
  loss = critic_loss.item<double>();
  return f;
}

torch::Tensor actor_features_of(ActorCritic& nets, const Observation& o, const ObservationSpec& spec,
                                const torch::Device& device) {
  return nets->actor_features(image_batch(o, spec, device), vector_batch(o, spec, device), {});
}

void step_unit_noise(double rho, int action_dims, std::mt19937_64& rng, std::vector<float>& z) {
  std::normal_distribution<float> normal(0.0f, 1.0f);
  if (z.empty()) {
    z.resize(static_cast<std::size_t>(action_dims));
    for (float& v : z) v = normal(rng);
    return;
  }
  const auto r = static_cast<float>(rho), innovation = static_cast<float>(std::sqrt(1.0 - rho * rho));
  for (float& v : z) v = r * v + innovation * normal(rng);
}

bool random_warmup_action(std::int64_t random_action_steps, std::int64_t random_action_episodes,
                          const LearnerCounters& n, bool explore, double rho, std::mt19937_64& rng,
                          std::vector<float>& noise, Action& action) {
  if (!explore || !in_random_warmup(random_action_steps, random_action_episodes, n)) return false;
  if (rho > 0) {
    step_unit_noise(rho, static_cast<int>(action.continuous.size()), rng, noise);
    for (std::size_t i = 0; i < action.continuous.size(); ++i)
      action.continuous[i] = static_cast<float>(std::erf(noise[i] / std::sqrt(2.0)));
    return true;
  }
  std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
  for (float& a : action.continuous) a = uniform(rng);
  return true;
}

void OffPolicyLearner::store(const Observation& o, const Action& action, float reward, const Observation& next,
                             bool terminated, bool truncated, int steps) {
  replay_.add(o, action, reward, next, terminated,
              static_cast<float>(std::pow(schedule_.gamma, discount_steps(steps))));
  ++counters_.transitions;
  if (terminated || truncated) {
    ++counters_.episodes;
    acting_.start_episode();
  }
}

int OffPolicyLearner::updates_due() const {
  if (counters_.transitions < schedule_.learning_starts) return 0;
  return counters_.transitions % schedule_.train_frequency == 0 ? schedule_.gradient_steps : 0;
}

void OffPolicyLearner::save_to(const std::string& path, bool with_replay) const {
  torch::serialize::OutputArchive a;
  write_common(a, counters_, rng_, algorithm_);
  const CheckpointParts parts = checkpoint_parts();
  for (const auto& [key, module] : parts.modules) {
    torch::serialize::OutputArchive part;
    module->save(part);
    a.write(key, part);
  }
  write_extra(a);
  for (const auto& [key, optimizer] : parts.optimizers) {
    torch::serialize::OutputArchive part;
    optimizer->save(part);
    a.write(key, part);
  }
  write_replay(a, replay_, with_replay);
  save_archive(a, path);
}

const ActionSpec& OffPolicyLearner::nonempty(const std::string& algorithm, const ActionSpec& action) {
  if (action.size < 1)
    throw std::invalid_argument(algorithm + ": need at least one action" +
                                (action.kind == ActionKind::kContinuous ? " dimension" : ""));
  return action;
}

void OffPolicyLearner::save_policy(const std::string& path) const {
  save_policy_file(path, acting_module(), key_, counters_, rng_, algorithm_);
}

void OffPolicyLearner::load_acting_networks(const std::string& path) {
  torch::serialize::InputArchive a, nets;
  a.load_from(path, device_);
  a.read(key_, nets);  // a policy file's networks, or a full checkpoint's online networks
  acting_module().load(nets);
  const CheckpointParts parts = checkpoint_parts();
  for (const auto& [key, optimizer] : parts.optimizers) optimizer->rebind();
  for (FlatParameters* f : parts.flat) f->rebind();
}

void OffPolicyLearner::load(const std::string& path) {
  torch::serialize::InputArchive a;
  a.load_from(path, device_);
  read_common(a, counters_, rng_, algorithm_);
  const CheckpointParts parts = checkpoint_parts();
  if (!read_policy_only(a, key_, acting_module())) {
    for (const auto& [key, module] : parts.modules) {
      torch::serialize::InputArchive part;
      a.read(key, part);
      module->load(part);
    }
    read_extra(a);
    for (const auto& [key, optimizer] : parts.optimizers) {
      torch::serialize::InputArchive part;
      a.read(key, part);
      optimizer->load(part);
    }
    read_replay(a, replay_);
  }
  // A module load gave the parameters new storage: make them views of the flat buffers again.
  for (const auto& [key, optimizer] : parts.optimizers) optimizer->rebind();
  for (FlatParameters* f : parts.flat) f->rebind();
}

}  // namespace comorph::rl
