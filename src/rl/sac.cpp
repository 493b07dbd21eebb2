#include "rl/sac.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace comorph::rl {

Sac::Sac(const ObservationSpec& observation, int action_dims, const SacConfig& config,
         std::uint64_t seed)
    : spec_(observation), action_dims_(action_dims), config_(config), device_(config.device),
      replay_(observation, {ActionKind::kContinuous, action_dims}, config.buffer_size,
              image_storage_from_string(config.image_storage)),
      rng_(seed) {
  if (action_dims < 1) throw std::invalid_argument("Sac: need at least one action dimension");
  torch::manual_seed(seed);  // network initialisation
  auto make = [&] {
    // The actor outputs a mean and a log-std per action dimension.
    return ActorCritic(spec_, action_dims, 2 * action_dims, config.hidden_sizes,
                       config.image_features, config.image_fc_size, config.share_encoder);
  };
  nets_ = make();
  target_ = make();
  nets_->to(device_);
  target_->to(device_);
  copy_parameters(*target_, *nets_);
  log_alpha_ = torch::full({1}, std::log(config.alpha),
                           torch::TensorOptions().dtype(torch::kFloat32).device(device_))
                   .set_requires_grad(true);
  actor_optimizer_ = std::make_unique<torch::optim::Adam>(
      nets_->actor_parameters(), torch::optim::AdamOptions(config.actor_learning_rate));
  critic_optimizer_ = std::make_unique<torch::optim::Adam>(
      nets_->critic_parameters(), torch::optim::AdamOptions(config.critic_learning_rate));
  alpha_optimizer_ = std::make_unique<torch::optim::Adam>(
      std::vector<torch::Tensor>{log_alpha_}, torch::optim::AdamOptions(config.alpha_learning_rate));
}

double Sac::alpha() const { return std::exp(log_alpha_.item<double>()); }

torch::Tensor Sac::standard_normal(std::int64_t rows, std::int64_t cols) {
  // Drawn from the learner's own generator so that a checkpoint restores it.
  torch::Tensor noise = torch::empty({rows, cols}, torch::kFloat32);
  float* p = noise.data_ptr<float>();
  std::normal_distribution<float> normal(0.0f, 1.0f);
  for (std::int64_t i = 0; i < rows * cols; ++i) p[i] = normal(rng_);
  return noise.to(device_);
}

std::pair<torch::Tensor, torch::Tensor> Sac::sample_action(const torch::Tensor& features) {
  const torch::Tensor out = nets_->actor_head(features);
  const torch::Tensor mean = out.slice(1, 0, action_dims_);
  torch::Tensor log_std = torch::tanh(out.slice(1, action_dims_, 2 * action_dims_));
  log_std = config_.log_std_min + 0.5 * (config_.log_std_max - config_.log_std_min) * (log_std + 1);
  const torch::Tensor eps = standard_normal(features.size(0), action_dims_);
  const torch::Tensor x = mean + log_std.exp() * eps;  // reparameterised
  const torch::Tensor y = torch::tanh(x);
  // log N(x; mean, std) minus the tanh change of variables, summed over dims.
  const torch::Tensor log_prob =
      (-0.5 * eps.pow(2) - log_std - 0.5 * std::log(2 * M_PI) - torch::log(1 - y.pow(2) + 1e-6))
          .sum(1);
  return {y, log_prob};
}

void Sac::act(const Observation& o, bool explore, Action& action) {
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
    const torch::Tensor f = nets_->actor_features(image, vector, {});
    if (explore) {
      a = sample_action(f).first;
    } else {
      a = torch::tanh(nets_->actor_head(f).slice(1, 0, action_dims_));  // the mean action
    }
    a = a.to(torch::kCPU);
  }
  std::copy(a.data_ptr<float>(), a.data_ptr<float>() + action_dims_, action.continuous.begin());
}

void Sac::store(const Observation& o, const Action& action, float reward, const Observation& next,
                bool terminated, bool truncated, int steps) {
  replay_.add(o, action, reward, next, terminated, static_cast<float>(std::pow(config_.gamma, steps)));
  ++counters_.transitions;
  if (terminated || truncated) ++counters_.episodes;
}

int Sac::updates_due() const {
  if (counters_.transitions < config_.learning_starts) return 0;
  return counters_.transitions % config_.train_frequency == 0 ? config_.gradient_steps : 0;
}

void Sac::update() {
  const ReplayBatch b = replay_.sample(config_.batch_size, rng_, device_);
  const double alpha_now = alpha();

  // Soft target: r + gamma^k (1 - terminated) (min Q'(s', a') - alpha log pi(a'|s')),
  // a' ~ pi(s'). The actor reads the target encoder's features of s' (one
  // convolution for both uses; the target encoder trails the online one).
  torch::Tensor y;
  {
    torch::NoGradGuard no_grad;
    const torch::Tensor next_f = target_->critic_features(b.next_image, b.next_vector);
    const torch::Tensor next_actor_f =
        nets_->shares_encoder() ? next_f : nets_->actor_features(b.next_image, b.next_vector, {});
    auto [next_a, next_log_prob] = sample_action(next_actor_f);
    const torch::Tensor next_q =
        torch::min(target_->q1(next_f, next_a), target_->q2(next_f, next_a)) - alpha_now * next_log_prob;
    y = b.reward + b.bootstrap * next_q;
  }
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

  if (counters_.updates % config_.policy_frequency == 0) {
    const torch::Tensor critic_f = f.detach();
    // Delayed as in TD3, compensated by doing policy_frequency actor steps.
    for (int i = 0; i < config_.policy_frequency; ++i) {
      const torch::Tensor actor_f = nets_->actor_features(b.image, b.vector, critic_f);
      auto [a, log_prob] = sample_action(actor_f);
      const torch::Tensor q = torch::min(nets_->q1(critic_f, a), nets_->q2(critic_f, a));
      const torch::Tensor actor_loss = (alpha() * log_prob - q).mean();
      actor_optimizer_->zero_grad();
      actor_loss.backward();
      if (config_.max_grad_norm > 0)
        torch::nn::utils::clip_grad_norm_(nets_->actor_parameters(), config_.max_grad_norm);
      actor_optimizer_->step();
      if (config_.autotune_alpha) {
        const double target_entropy = -config_.target_entropy_scale * action_dims_;
        const torch::Tensor alpha_loss =
            (-log_alpha_.exp() * (log_prob.detach() + target_entropy)).mean();
        alpha_optimizer_->zero_grad();
        alpha_loss.backward();
        alpha_optimizer_->step();
      }
    }
  }
  if (counters_.updates % config_.target_network_frequency == 0) {
    soft_update(*target_->critic_encoder, *nets_->critic_encoder, config_.tau);
    soft_update(*target_->critic1, *nets_->critic1, config_.tau);
    soft_update(*target_->critic2, *nets_->critic2, config_.tau);
  }
}

void Sac::save(const std::string& path) const { save_to(path, true); }
void Sac::save_without_replay(const std::string& path) const { save_to(path, false); }

void Sac::save_to(const std::string& path, bool with_replay) const {
  torch::serialize::OutputArchive a, nets, target, actor_opt, critic_opt, alpha_opt;
  write_common(a, counters_, rng_, "sac");
  nets_->save(nets);
  target_->save(target);
  actor_optimizer_->save(actor_opt);
  critic_optimizer_->save(critic_opt);
  alpha_optimizer_->save(alpha_opt);
  a.write("networks", nets);
  a.write("target_networks", target);
  a.write("log_alpha", log_alpha_.detach());
  a.write("actor_optimizer", actor_opt);
  a.write("critic_optimizer", critic_opt);
  a.write("alpha_optimizer", alpha_opt);
  write_replay(a, replay_, with_replay);
  save_archive(a, path);
}

void Sac::save_policy(const std::string& path) const {
  save_policy_file(path, *nets_, "networks", counters_, rng_, "sac");
}

void Sac::load(const std::string& path) {
  torch::serialize::InputArchive a, nets, target, actor_opt, critic_opt, alpha_opt;
  a.load_from(path, device_);
  read_common(a, counters_, rng_, "sac");
  if (read_policy_only(a, "networks", *nets_)) return;
  a.read("networks", nets);
  a.read("target_networks", target);
  a.read("actor_optimizer", actor_opt);
  a.read("critic_optimizer", critic_opt);
  a.read("alpha_optimizer", alpha_opt);
  nets_->load(nets);
  target_->load(target);
  torch::Tensor log_alpha;
  a.read("log_alpha", log_alpha);
  {
    torch::NoGradGuard no_grad;
    log_alpha_.copy_(log_alpha);
  }
  actor_optimizer_->load(actor_opt);
  critic_optimizer_->load(critic_opt);
  alpha_optimizer_->load(alpha_opt);
  read_replay(a, replay_);
}

}  // namespace comorph::rl
