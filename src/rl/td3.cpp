#include "rl/td3.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace comorph::rl {

Td3::Td3(const ObservationSpec& observation, int action_dims, const Td3Config& config,
         std::uint64_t seed)
    : spec_(observation), action_dims_(action_dims), config_(config), device_(config.device),
      replay_(observation, {ActionKind::kContinuous, action_dims}, config.buffer_size,
              image_storage_from_string(config.image_storage)),
      rng_(seed) {
  if (action_dims < 1) throw std::invalid_argument("Td3: need at least one action dimension");
  torch::manual_seed(seed);  // network initialisation
  auto make = [&] {
    return ActorCritic(spec_, action_dims, action_dims, config.hidden_sizes, config.image_features,
                       config.image_fc_size, config.share_encoder);
  };
  nets_ = make();
  target_ = make();
  nets_->to(device_);
  target_->to(device_);
  copy_parameters(*target_, *nets_);
  actor_optimizer_ = std::make_unique<torch::optim::Adam>(
      nets_->actor_parameters(), torch::optim::AdamOptions(config.actor_learning_rate));
  critic_optimizer_ = std::make_unique<torch::optim::Adam>(
      nets_->critic_parameters(), torch::optim::AdamOptions(config.critic_learning_rate));
}

double Td3::exploration_noise() const {
  const double t = config_.exploration_noise_unit == "episodes"
                       ? static_cast<double>(counters_.episodes)
                       : static_cast<double>(counters_.transitions);
  return LinearSchedule{config_.exploration_noise_start, config_.exploration_noise_end,
                        config_.exploration_noise_decay}
      .at(t);
}

double Td3::bc_weight_now() const {
  if (config_.bc_decay_updates <= 0) return config_.bc_weight;
  return LinearSchedule{config_.bc_weight, 0.0, static_cast<double>(config_.bc_decay_updates)}.at(
      static_cast<double>(counters_.updates));
}

torch::Tensor Td3::gaussian(std::int64_t rows, std::int64_t cols, double std) {
  // Drawn from the learner's own generator so that a checkpoint restores it.
  torch::Tensor noise = torch::empty({rows, cols}, torch::kFloat32);
  float* p = noise.data_ptr<float>();
  std::normal_distribution<float> normal(0.0f, static_cast<float>(std));
  for (std::int64_t i = 0; i < rows * cols; ++i) p[i] = normal(rng_);
  return noise.to(device_);
}

void Td3::act(const Observation& o, bool explore, Action& action) {
  action.continuous.resize(action_dims_);
  if (explore && (counters_.transitions < config_.random_action_steps ||
                  counters_.episodes < config_.random_action_episodes)) {
    std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
    for (float& a : action.continuous) a = uniform(rng_);
    return;
  }
  torch::Tensor a;
  {
    torch::InferenceMode guard;
    const torch::Tensor image = image_batch(o, spec_, device_);
    const torch::Tensor vector = vector_batch(o, spec_, device_);
    a = torch::tanh(nets_->actor_head(nets_->actor_features(image, vector, {}))).to(torch::kCPU);
  }
  const float* p = a.data_ptr<float>();
  const double sigma = exploration_noise();
  std::normal_distribution<float> normal(0.0f, static_cast<float>(sigma));
  for (int i = 0; i < action_dims_; ++i) {
    float v = p[i];
    if (explore) v = std::clamp(v + normal(rng_), -1.0f, 1.0f);
    action.continuous[i] = v;
  }
}

void Td3::store(const Observation& o, const Action& action, float reward, const Observation& next,
                bool terminated, bool truncated, int steps) {
  replay_.add(o, action, reward, next, terminated, static_cast<float>(std::pow(config_.gamma, steps)));
  ++counters_.transitions;
  if (terminated || truncated) ++counters_.episodes;
}

int Td3::updates_due() const {
  if (counters_.transitions < config_.learning_starts) return 0;
  return counters_.transitions % config_.train_frequency == 0 ? config_.gradient_steps : 0;
}

void Td3::update() {
  const ReplayBatch b = replay_.sample(config_.batch_size, rng_, device_);
  const torch::Tensor smoothing =
      gaussian(config_.batch_size, action_dims_, config_.policy_noise)
          .clamp(-config_.noise_clip, config_.noise_clip);

  // Critic target: r + gamma^k (1 - terminated) min(Q1', Q2')(s', pi'(s') + clipped noise).
  torch::Tensor y;
  {
    torch::NoGradGuard no_grad;
    const torch::Tensor next_f = target_->critic_features(b.next_image, b.next_vector);
    const torch::Tensor next_actor_f = target_->actor_features(b.next_image, b.next_vector, next_f);
    const torch::Tensor next_a = (torch::tanh(target_->actor_head(next_actor_f)) + smoothing).clamp(-1.0, 1.0);
    const torch::Tensor next_q = torch::min(target_->q1(next_f, next_a), target_->q2(next_f, next_a));
    y = b.reward + b.bootstrap * next_q;
  }
  // The encoder runs once; both critics read its features.
  const torch::Tensor f = nets_->critic_features(b.image, b.vector);
  const torch::Tensor critic_loss =
      torch::mse_loss(nets_->q1(f, b.action), y) + torch::mse_loss(nets_->q2(f, b.action), y);
  critic_optimizer_->zero_grad();
  critic_loss.backward();
  if (config_.max_grad_norm > 0)
    torch::nn::utils::clip_grad_norm_(nets_->critic_parameters(), config_.max_grad_norm);
  critic_optimizer_->step();
  last_loss_ = critic_loss.item<double>();
  ++counters_.updates;

  if (counters_.updates % config_.policy_delay == 0) {
    // Delayed actor update: maximise Q1(s, pi(s)). The critic's features are
    // taken detached (computed before the critic step above; the encoder
    // learns from the critic loss only).
    const torch::Tensor critic_f = f.detach();
    const torch::Tensor actor_f = nets_->actor_features(b.image, b.vector, critic_f);
    const torch::Tensor pi = torch::tanh(nets_->actor_head(actor_f));
    const torch::Tensor q = nets_->q1(critic_f, pi);
    torch::Tensor actor_loss;
    if (config_.bc_weight > 0) {
      // Q normalised by its batch magnitude, so that w means the same at any reward scale.
      const double w = bc_weight_now();
      actor_loss = -q.mean() / q.abs().mean().detach().clamp_min(1e-6);
      if (w > 0)
        actor_loss = actor_loss + w * ((pi - b.target).pow(2).sum(1) * b.has_target).mean();
    } else {
      actor_loss = -q.mean();
    }
    actor_optimizer_->zero_grad();
    actor_loss.backward();
    if (config_.max_grad_norm > 0)
      torch::nn::utils::clip_grad_norm_(nets_->actor_parameters(), config_.max_grad_norm);
    actor_optimizer_->step();
    soft_update(*target_, *nets_, config_.tau);
  }
}

void Td3::save(const std::string& path) const { save_to(path, true); }
void Td3::save_without_replay(const std::string& path) const { save_to(path, false); }

void Td3::save_to(const std::string& path, bool with_replay) const {
  torch::serialize::OutputArchive a, nets, target, actor_opt, critic_opt;
  write_common(a, counters_, rng_, "td3");
  nets_->save(nets);
  target_->save(target);
  actor_optimizer_->save(actor_opt);
  critic_optimizer_->save(critic_opt);
  a.write("networks", nets);
  a.write("target_networks", target);
  a.write("actor_optimizer", actor_opt);
  a.write("critic_optimizer", critic_opt);
  write_replay(a, replay_, with_replay);
  save_archive(a, path);
}

void Td3::save_policy(const std::string& path) const {
  save_policy_file(path, *nets_, "networks", counters_, rng_, "td3");
}

void Td3::load(const std::string& path) {
  torch::serialize::InputArchive a, nets, target, actor_opt, critic_opt;
  a.load_from(path, device_);
  read_common(a, counters_, rng_, "td3");
  if (read_policy_only(a, "networks", *nets_)) return;
  a.read("networks", nets);
  a.read("target_networks", target);
  a.read("actor_optimizer", actor_opt);
  a.read("critic_optimizer", critic_opt);
  nets_->load(nets);
  target_->load(target);
  actor_optimizer_->load(actor_opt);
  critic_optimizer_->load(critic_opt);
  read_replay(a, replay_);
}

}  // namespace comorph::rl
