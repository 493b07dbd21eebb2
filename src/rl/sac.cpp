#include "rl/sac.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

namespace comorph::rl {
namespace {

ActorCritic make_networks(const ObservationSpec& spec, int action_dims, const SacConfig& c) {
  if (spec.head_selector > 0)
    throw std::invalid_argument("sac: actor heads (an observation with a head selector) are TD3's only");
  // The actor outputs a mean and a log-std per action dimension.
  ActorCritic nets(spec, action_dims, 2 * action_dims, c.hidden_sizes, c.image_features, c.image_fc_size,
                   c.share_encoder);
  nets->to(torch::Device(c.device));
  return nets;
}

// The actor's Gaussian from its features: the mean and the log std, bounded
// to [log_std_min, log_std_max].
std::pair<torch::Tensor, torch::Tensor> mean_and_log_std(ActorCritic& nets, const SacConfig& c, int action_dims,
                                                         const torch::Tensor& features) {
  const torch::Tensor out = nets->actor_head(features);
  const torch::Tensor log_std = torch::tanh(out.slice(1, action_dims, 2 * action_dims));
  return {out.slice(1, 0, action_dims), c.log_std_min + 0.5 * (c.log_std_max - c.log_std_min) * (log_std + 1)};
}

// Squashed Gaussian sample and its log-probability, from actor features.
std::pair<torch::Tensor, torch::Tensor> sample_action(ActorCritic& nets, const SacConfig& c, int action_dims,
                                                      const torch::Tensor& features, std::mt19937_64& rng,
                                                      const torch::Device& device) {
  const auto [mean, log_std] = mean_and_log_std(nets, c, action_dims, features);
  const torch::Tensor eps = gaussian_noise(features.size(0), action_dims, 1.0, rng, device);
  const torch::Tensor x = mean + log_std.exp() * eps;  // reparameterised
  const torch::Tensor y = torch::tanh(x);
  // log N(x; mean, std) minus the tanh change of variables, summed over dims.
  const torch::Tensor log_prob =
      (-0.5 * eps.pow(2) - log_std - 0.5 * std::log(2 * M_PI) - torch::log(1 - y.pow(2) + 1e-6)).sum(1);
  return {y, log_prob};
}

// The acting rule of the learner and of its Policy: random actions during the
// random-action warm-up, else a sample of the squashed Gaussian (exploring) or its mean.
// With exploration_noise_correlation rho > 0 the sample's unit noise, like the
// warm-up's actions, follows the AR(1) process of step_unit_noise.
void act_with(ActorCritic& nets, const ObservationSpec& spec, int action_dims, const SacConfig& c,
              const torch::Device& device, const LearnerCounters& n, std::mt19937_64& rng, ActingState& state,
              const Observation& o, bool explore, Action& action) {
  act_continuous(c, action_dims, n, explore, rng, state, action, [&](float* out) {
    copy_tensor_action(
        [&] {
          const torch::Tensor f = actor_features_of(nets, o, spec, device);
          if (!explore) return torch::tanh(nets->actor_head(f).slice(1, 0, action_dims));  // the mean action
          const double rho = c.exploration_noise_correlation;
          if (rho > 0) step_unit_noise(rho, action_dims, rng, state.noise);
          const torch::Tensor eps = rho > 0 ? torch::from_blob(state.noise.data(), {1, action_dims}).to(device)
                                            : gaussian_noise(1, action_dims, 1.0, rng, device);
          const auto [mean, log_std] = mean_and_log_std(nets, c, action_dims, f);
          return torch::tanh(mean + log_std.exp() * eps);
        },
        out);
  });
}

}  // namespace

Sac::Sac(const ObservationSpec& observation, int action_dims, const SacConfig& config, std::uint64_t seed)
    : OffPolicyLearner("sac", "networks", observation, {ActionKind::kContinuous, action_dims}, config, seed),
      action_dims_(action_dims), config_(config) {
  build_networks(seed, nets_, target_, [&] { return make_networks(spec_, action_dims, config); });
  log_alpha_ = torch::full({1}, std::log(config.alpha),
                           torch::TensorOptions().dtype(torch::kFloat32).device(device_))
                   .set_requires_grad(true);
  actor_optimizer_ = make_adam(nets_->actor_parameters(), config.actor_learning_rate);
  critic_optimizer_ = make_adam(nets_->critic_parameters(), config.critic_learning_rate);
  alpha_optimizer_ = make_adam({log_alpha_}, config.alpha_learning_rate);
  target_critic_ = FlatParameters(target_->critic_parameters(), /*with_grad=*/false);
}

double Sac::alpha() const { return std::exp(log_alpha_.item<double>()); }

void Sac::act(const Observation& o, bool explore, Action& action) {
  act_with(nets_, spec_, action_dims_, config_, device_, counters_, rng_, acting_, o, explore, action);
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
    auto [next_a, next_log_prob] = sample_action(nets_, config_, action_dims_, next_actor_f, rng_, device_);
    const torch::Tensor next_q =
        torch::min(target_->q1(next_f, next_a), target_->q2(next_f, next_a)) - alpha_now * next_log_prob;
    y = b.reward + b.bootstrap * next_q;
  }
  const torch::Tensor f = twin_critic_step(nets_, *critic_optimizer_, b, y, config_.max_grad_norm, last_loss_);
  ++counters_.updates;

  if (counters_.updates % config_.policy_frequency == 0) {
    const torch::Tensor critic_f = f.detach();
    // Delayed as in TD3, compensated by doing policy_frequency actor steps.
    for (int i = 0; i < config_.policy_frequency; ++i) {
      const torch::Tensor actor_f = nets_->actor_features(b.image, b.vector, critic_f);
      auto [a, log_prob] = sample_action(nets_, config_, action_dims_, actor_f, rng_, device_);
      const torch::Tensor q = torch::min(nets_->q1(critic_f, a), nets_->q2(critic_f, a));
      const torch::Tensor actor_loss = (alpha() * log_prob - q).mean();
      gradient_step(*actor_optimizer_, actor_loss, config_.max_grad_norm);
      if (config_.autotune_alpha) {
        const double target_entropy = -config_.target_entropy_scale * action_dims_;
        const torch::Tensor alpha_loss =
            (-log_alpha_.exp() * (log_prob.detach() + target_entropy)).mean();
        gradient_step(*alpha_optimizer_, alpha_loss, 0);
      }
    }
  }
  if (counters_.updates % config_.target_network_frequency == 0) {
    soft_update(target_critic_, critic_optimizer_->parameters(), config_.tau);
  }
}

Sac::CheckpointParts Sac::checkpoint_parts() const {
  return {{{"networks", nets_.ptr().get()}, {"target_networks", target_.ptr().get()}},
          {{"actor_optimizer", actor_optimizer_.get()},
           {"critic_optimizer", critic_optimizer_.get()},
           {"alpha_optimizer", alpha_optimizer_.get()}},
          {&target_critic_}};
}

void Sac::write_extra(torch::serialize::OutputArchive& a) const { a.write("log_alpha", log_alpha_.detach()); }

void Sac::read_extra(torch::serialize::InputArchive& a) {
  torch::Tensor log_alpha;
  a.read("log_alpha", log_alpha);
  torch::NoGradGuard no_grad;
  log_alpha_.copy_(log_alpha);
}

std::unique_ptr<Policy> Sac::policy(const ObservationSpec& observation, int action_dims, const SacConfig& config,
                                    std::uint64_t seed) {
  return make_network_policy("sac", "networks", observation, action_dims, config, seed, &make_networks, &act_with);
}

}  // namespace comorph::rl
