#include "rl/td3.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace comorph::rl {
namespace {

ActorCritic make_networks(const ObservationSpec& spec, int action_dims, const Td3Config& c) {
  if (spec.head_selector < 0 || spec.head_selector > spec.vector_size)
    throw std::invalid_argument("td3: the observation's head selector (" + std::to_string(spec.head_selector) +
                                " values) does not fit its vector of " + std::to_string(spec.vector_size));
  ActorCritic nets(spec, action_dims, action_dims * spec.actor_heads(), c.hidden_sizes, c.image_features,
                   c.image_fc_size, c.share_encoder);
  nets->to(torch::Device(c.device));
  return nets;
}

double noise_std(const Td3Config& c, const LearnerCounters& n) {
  const double t = c.exploration_noise_unit == NoiseDecayUnit::episodes ? static_cast<double>(n.episodes)
                                                                        : static_cast<double>(n.transitions);
  return LinearSchedule{c.exploration_noise_start, c.exploration_noise_end, c.exploration_noise_decay}.at(t);
}

// The action outputs ([B, A]) of each row's chosen head, of the actor's
// outputs [B, heads x A]; `vector` [B, V] holds the selector.
torch::Tensor chosen_heads(const torch::Tensor& outputs, const ObservationSpec& spec, const torch::Tensor& vector,
                           int action_dims) {
  if (spec.head_selector == 0) return outputs;
  const torch::Tensor head = vector.slice(1, spec.vector_size - spec.head_selector).argmax(1);
  return outputs.view({-1, spec.head_selector, action_dims})
      .gather(1, head.view({-1, 1, 1}).expand({-1, 1, action_dims}))
      .squeeze(1);
}

// tanh of the actor's output (its chosen head's) for one vector observation
// on the CPU: the row pass, then LibTorch's tanh on preallocated tensors; the
// same bits as the tensor path, without its dispatch.
void squashed_actor_row(ActorCritic& nets, const ObservationSpec& spec, int action_dims, const Observation& o,
                        ActingState& state, float* out) {
  check_vector_size(o, spec);
  const float* outputs = state.actor.forward(nets->actor, o.vector.data());
  const int head = spec.head_of(o.vector.data());  // 0 without heads
  torch::InferenceMode guard;
  if (!state.head_output.defined()) {
    state.head_output = torch::empty({1, action_dims});
    state.squashed = torch::empty({1, action_dims});
  }
  std::copy_n(outputs + head * action_dims, action_dims, state.head_output.data_ptr<float>());
  at::tanh_out(state.squashed, state.head_output);
  std::copy_n(state.squashed.data_ptr<float>(), action_dims, out);
}

// The acting rule of the learner and of its Policy: random actions during the
// random-action warm-up, else tanh(actor) plus clipped noise when exploring.
// With exploration_noise_correlation 0 both are white (uniform actions,
// Gaussian noise); with rho > 0 both follow step_unit_noise's AR(1) process (the
// warm-up's action erf(z / sqrt 2) is uniform in [-1, 1] at every step).
void act_with(ActorCritic& nets, const ObservationSpec& spec, int action_dims, const Td3Config& c,
              const torch::Device& device, const LearnerCounters& n, std::mt19937_64& rng, ActingState& state,
              const Observation& o, bool explore, Action& action) {
  const double rho = c.exploration_noise_correlation;
  const bool from_actor = act_continuous(c, action_dims, n, explore, rng, state, action, [&](float* out) {
    if (!spec.has_image() && device.is_cpu() && MlpPass::supports(nets->actor))
      return squashed_actor_row(nets, spec, action_dims, o, state, out);
    copy_tensor_action(
        [&] {
          const torch::Tensor outputs = nets->actor_head(actor_features_of(nets, o, spec, device));
          if (spec.head_selector == 0) return torch::tanh(outputs);
          const int head = spec.head_of(o.vector.data());
          return torch::tanh(outputs.slice(1, head * action_dims, (head + 1) * action_dims));
        },
        out);
  });
  if (!from_actor || !explore) return;
  if (rho <= 0) {
    std::normal_distribution<float> normal(0.0f, static_cast<float>(noise_std(c, n)));
    for (float& v : action.continuous) v = std::clamp(v + normal(rng), -1.0f, 1.0f);
    return;
  }
  step_unit_noise(rho, action_dims, rng, state.noise);
  const auto std = static_cast<float>(noise_std(c, n));
  for (int i = 0; i < action_dims; ++i)
    action.continuous[i] = std::clamp(action.continuous[i] + std * state.noise[i], -1.0f, 1.0f);
}

}  // namespace

Td3::Td3(const ObservationSpec& observation, int action_dims, const Td3Config& config, std::uint64_t seed)
    : OffPolicyLearner("td3", "networks", observation, {ActionKind::kContinuous, action_dims}, config, seed),
      action_dims_(action_dims), config_(config) {
  build_networks(seed, nets_, target_, [&] { return make_networks(spec_, action_dims, config); });
  actor_optimizer_ = make_adam(nets_->actor_parameters(), config.actor_learning_rate);
  critic_optimizer_ = make_adam(nets_->critic_parameters(), config.critic_learning_rate);
  target_actor_ = FlatParameters(target_->actor_parameters(), /*with_grad=*/false);
  target_critic_ = FlatParameters(target_->critic_parameters(), /*with_grad=*/false);
}

double Td3::exploration_noise() const { return noise_std(config_, counters_); }

double Td3::bc_weight_now() const {
  if (config_.bc_decay_updates <= 0) return config_.bc_weight;
  return LinearSchedule{config_.bc_weight, 0.0, static_cast<double>(config_.bc_decay_updates)}.at(
      static_cast<double>(counters_.updates));
}

void Td3::act(const Observation& o, bool explore, Action& action) {
  act_with(nets_, spec_, action_dims_, config_, device_, counters_, rng_, acting_, o, explore, action);
}

void Td3::update() {
  replay_.sample_into(batch_, config_.batch_size, rng_, device_);
  const torch::Tensor smoothing =
      gaussian_noise(config_.batch_size, action_dims_, config_.policy_noise, rng_, device_)
          .clamp(-config_.noise_clip, config_.noise_clip);
  if (spec_.has_image() || force_autograd_ || !MlpPass::supports(nets_->actor))
    update_with_autograd(batch_, smoothing);
  else
    update_with_explicit_passes(batch_, smoothing);
}

void Td3::update_with_autograd(const ReplayBatch& b, const torch::Tensor& smoothing) {
  // Critic target: r + gamma^k (1 - terminated) min(Q1', Q2')(s', pi'(s') + clipped noise).
  torch::Tensor y;
  {
    torch::NoGradGuard no_grad;
    const torch::Tensor next_f = target_->critic_features(b.next_image, b.next_vector);
    const torch::Tensor next_actor_f = target_->actor_features(b.next_image, b.next_vector, next_f);
    const torch::Tensor next_pi = chosen_heads(target_->actor_head(next_actor_f), spec_, b.next_vector, action_dims_);
    const torch::Tensor next_a = (torch::tanh(next_pi) + smoothing).clamp(-1.0, 1.0);
    const torch::Tensor next_q = torch::min(target_->q1(next_f, next_a), target_->q2(next_f, next_a));
    y = b.reward + b.bootstrap * next_q;
  }
  const torch::Tensor f = twin_critic_step(nets_, *critic_optimizer_, b, y, config_.max_grad_norm, last_loss_);
  ++counters_.updates;

  if (counters_.updates % config_.policy_delay == 0) {
    // Delayed actor update: maximise Q1(s, pi(s)). The critic's features are
    // taken detached (computed before the critic step above; the encoder
    // learns from the critic loss only).
    const torch::Tensor critic_f = f.detach();
    const torch::Tensor actor_f = nets_->actor_features(b.image, b.vector, critic_f);
    const torch::Tensor pi = torch::tanh(chosen_heads(nets_->actor_head(actor_f), spec_, b.vector, action_dims_));
    const torch::Tensor q = nets_->q1(critic_f, pi);
    // With behaviour cloning, Q normalised by its batch magnitude, so that w means the same at any reward scale.
    const bool bc = config_.bc_weight > 0;
    torch::Tensor actor_loss = bc ? -q.mean() / q.abs().mean().detach().clamp_min(1e-6) : -q.mean();
    if (config_.actor_q_weight != 1) actor_loss = config_.actor_q_weight * actor_loss;
    const double w = bc ? bc_weight_now() : 0.0;
    if (w > 0) actor_loss = actor_loss + w * ((pi - b.target).pow(2).sum(1) * b.has_target).mean();
    gradient_step(*actor_optimizer_, actor_loss, config_.max_grad_norm);
    actor_step_done();
  }
}

// The update above, pass by pass on the CPU (rl/mlp_pass.hpp): each gradient
// is the one autograd computes for the same loss, up to float rounding. The
// observation is the vector alone, so the critics' features are b.vector.
// Activations are feature-major ([features, batch]): element (j, r) of a
// [B, n] batch tensor is at r * n + j, of a pass's buffer at j * B + r.
// With actor heads, row r's action j is the actor's output
// (head[r] * A + j, r); the other heads' outputs get no gradient from it.
void Td3::update_with_explicit_passes(const ReplayBatch& b, const torch::Tensor& smoothing) {
  const int batch = static_cast<int>(config_.batch_size), obs = spec_.vector_size, act = action_dims_;
  if (!explicit_) {
    const auto size = [&](int n) { return std::vector<float>(static_cast<std::size_t>(batch) * n); };
    explicit_ = std::make_unique<ExplicitUpdate>(ExplicitUpdate{
        MlpPass(nets_->actor, batch), MlpPass(nets_->critic1, batch), size(obs), size(obs), size(obs + act), size(1),
        size(1), size(act), size(act * spec_.actor_heads()), std::vector<int>(batch), std::vector<int>(batch)});
  }
  ExplicitUpdate& e = *explicit_;
  for (int r = 0; r < batch && spec_.head_selector > 0; ++r) {  // else every row's head stays 0
    e.head[r] = spec_.head_of(b.vector.data_ptr<float>() + static_cast<std::ptrdiff_t>(r) * obs);
    e.next_head[r] = spec_.head_of(b.next_vector.data_ptr<float>() + static_cast<std::ptrdiff_t>(r) * obs);
  }
  // Row r's action j among an actor's outputs [heads x A, B].
  const auto output_of = [&](const std::vector<int>& head, int j, int r) { return (head[r] * act + j) * batch + r; };
  // [B, n] batch-major into [n, B] feature-major.
  const auto transpose_into = [batch](const float* from, int n, float* to) {
    for (int r = 0; r < batch; ++r)
      for (int j = 0; j < n; ++j) to[static_cast<std::ptrdiff_t>(j) * batch + r] = from[static_cast<std::ptrdiff_t>(r) * n + j];
  };
  transpose_into(b.vector.data_ptr<float>(), obs, e.observation.data());
  transpose_into(b.next_vector.data_ptr<float>(), obs, e.next_observation.data());
  const float* reward = b.reward.data_ptr<float>();
  const float* bootstrap = b.bootstrap.data_ptr<float>();
  const float* noise = smoothing.data_ptr<float>();  // [B, A]
  // The critics' input cat({observation, action}, 1): its first obs rows, then the action's.
  float* const critic_action = e.critic_input.data() + static_cast<std::ptrdiff_t>(obs) * batch;
  const auto set_critic_observation = [&](const std::vector<float>& observation) {
    std::copy(observation.begin(), observation.end(), e.critic_input.begin());
  };
  const auto q_of = [&](Mlp& critic) { return e.critic.forward(critic, e.critic_input.data()); };

  // Critic target: r + gamma^k (1 - terminated) min(Q1', Q2')(s', pi'(s') + clipped noise).
  const float* next_outputs = e.actor.forward(target_->actor, e.next_observation.data());
  for (int j = 0; j < act; ++j)
    for (int r = 0; r < batch; ++r) {
      const float next_a = next_outputs[output_of(e.next_head, j, r)];
      critic_action[j * batch + r] = std::clamp(std::tanh(next_a) + noise[r * act + j], -1.0f, 1.0f);
    }
  set_critic_observation(e.next_observation);
  std::copy_n(q_of(target_->critic1), batch, e.y.data());
  const float* q2 = q_of(target_->critic2);
  for (int r = 0; r < batch; ++r) e.y[r] = reward[r] + bootstrap[r] * std::min(e.y[r], q2[r]);

  // Twin critics: MSE to y each; their parameters are disjoint, so one after the other.
  set_critic_observation(e.observation);
  transpose_into(b.action.data_ptr<float>(), act, critic_action);
  double loss = 0;
  for (Mlp* critic : {&nets_->critic1, &nets_->critic2}) {
    const float* q = q_of(*critic);
    double squares = 0;
    for (int r = 0; r < batch; ++r) {
      const float diff = q[r] - e.y[r];
      squares += static_cast<double>(diff) * diff;
      e.q_grad[r] = 2.0f * diff / static_cast<float>(batch);
    }
    loss += squares / batch;
    e.critic.backward(e.q_grad.data(), /*parameter_grads=*/true, /*input_grad=*/false);
  }
  clip_and_step(*critic_optimizer_, config_.max_grad_norm);
  last_loss_ = loss;
  ++counters_.updates;
  if (counters_.updates % config_.policy_delay != 0) return;

  // Delayed actor update: maximise Q1(s, pi(s)) (+ behaviour cloning).
  const float* outputs = e.actor.forward(nets_->actor, e.observation.data());
  float* const pi = e.pi.data();
  for (int j = 0; j < act; ++j)
    for (int r = 0; r < batch; ++r)
      critic_action[j * batch + r] = pi[j * batch + r] = std::tanh(outputs[output_of(e.head, j, r)]);
  const float* q = q_of(nets_->critic1);
  // d loss / d q of -mean(q) [/ mean|q|]: the same value for every row.
  double d_mean = -config_.actor_q_weight / batch;
  if (config_.bc_weight > 0) {
    double abs_sum = 0;
    for (int r = 0; r < batch; ++r) abs_sum += std::abs(q[r]);
    d_mean /= std::max(abs_sum / batch, 1e-6);
  }
  std::fill(e.q_grad.begin(), e.q_grad.end(), static_cast<float>(d_mean));
  e.critic.backward(e.q_grad.data(), /*parameter_grads=*/false, /*input_grad=*/true);
  // d loss / d pi, from the critic's input gradient, plus behaviour cloning's
  // w * mean(sum_j (pi - target)^2 * has_target), then through the tanh.
  const double w = config_.bc_weight > 0 ? bc_weight_now() : 0.0;
  const auto bc_scale = static_cast<float>(2.0 * w / batch);
  const float* target = b.target.data_ptr<float>();
  const float* has_target = b.has_target.data_ptr<float>();
  const float* d_critic_action = e.critic.input_grad() + static_cast<std::ptrdiff_t>(obs) * batch;
  if (spec_.head_selector > 0) std::fill(e.actor_output_grad.begin(), e.actor_output_grad.end(), 0.0f);
  for (int j = 0; j < act; ++j)
    for (int r = 0; r < batch; ++r) {
      const int i = j * batch + r;
      float d_pi = d_critic_action[i];
      if (w > 0) d_pi += bc_scale * has_target[r] * (pi[i] - target[r * act + j]);
      e.actor_output_grad[output_of(e.head, j, r)] = d_pi * (1.0f - pi[i] * pi[i]);
    }
  e.actor.backward(e.actor_output_grad.data(), /*parameter_grads=*/true, /*input_grad=*/false);
  clip_and_step(*actor_optimizer_, config_.max_grad_norm);
  actor_step_done();
}

void Td3::actor_step_done() {
  soft_update(target_actor_, actor_optimizer_->parameters(), config_.tau);
  soft_update(target_critic_, critic_optimizer_->parameters(), config_.tau);
}

Td3::CheckpointParts Td3::checkpoint_parts() const {
  return {{{"networks", nets_.ptr().get()}, {"target_networks", target_.ptr().get()}},
          {{"actor_optimizer", actor_optimizer_.get()}, {"critic_optimizer", critic_optimizer_.get()}},
          {&target_actor_, &target_critic_}};
}

std::unique_ptr<Policy> Td3::policy(const ObservationSpec& observation, int action_dims, const Td3Config& config,
                                    std::uint64_t seed) {
  return make_network_policy("td3", "networks", observation, action_dims, config, seed, &make_networks, &act_with);
}

}  // namespace comorph::rl
