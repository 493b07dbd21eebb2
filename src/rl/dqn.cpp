#include "rl/dqn.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

namespace comorph::rl {

namespace {

QNetwork make_network(const ObservationSpec& spec, int num_actions, const DqnConfig& c) {
  QNetwork q(spec, num_actions, c.hidden_sizes, c.image_features, c.image_fc_size, c.ensemble_size);
  q->to(torch::Device(c.device));
  return q;
}

double epsilon_at(const DqnConfig& c, const LearnerCounters& n) {
  return LinearSchedule{c.epsilon_start, c.epsilon_end, c.epsilon_decay}.at(static_cast<double>(n.transitions));
}

std::vector<float> q_values_of(QNetwork& q, const ObservationSpec& spec, int num_actions, const torch::Device& device,
                               const Observation& o) {
  torch::InferenceMode guard;
  torch::Tensor v = q->forward(image_batch(o, spec, device), vector_batch(o, spec, device)).to(torch::kCPU);
  return std::vector<float>(v.data_ptr<float>(), v.data_ptr<float>() + num_actions);
}

// The acting rule of the learner and of its Policy: epsilon-greedy among the
// observation's valid actions (the random choice uniform among them).
void act_with(QNetwork& q, const ObservationSpec& spec, int num_actions, const DqnConfig& c,
              const torch::Device& device, const LearnerCounters& n, std::mt19937_64& rng,
              ActingState& /*state: unused*/, const Observation& o, bool explore, Action& action) {
  const auto& mask = o.valid_actions;
  if (!mask.empty() && static_cast<int>(mask.size()) != num_actions)
    throw std::invalid_argument("Dqn::act: valid_actions has " + std::to_string(mask.size()) +
                                " entries, expected " + std::to_string(num_actions));
  auto valid = [&](int a) { return mask.empty() || mask[a] != 0; };
  int valid_count = 0;
  for (int a = 0; a < num_actions; ++a) valid_count += valid(a);
  if (valid_count == 0) throw std::invalid_argument("Dqn::act: no valid action in the mask");

  if (explore && std::uniform_real_distribution<double>(0.0, 1.0)(rng) < epsilon_at(c, n)) {
    int k = std::uniform_int_distribution<int>(0, valid_count - 1)(rng);
    for (int a = 0; a < num_actions; ++a)
      if (valid(a) && k-- == 0) {
        action.discrete = a;
        return;
      }
  }
  const std::vector<float> values = q_values_of(q, spec, num_actions, device, o);
  int best = -1;
  for (int a = 0; a < num_actions; ++a)
    if (valid(a) && (best < 0 || values[a] > values[best])) best = a;
  action.discrete = best;
}

}  // namespace

Dqn::Dqn(const ObservationSpec& observation, int num_actions, const DqnConfig& config, std::uint64_t seed)
    : OffPolicyLearner("dqn", "q", observation, {ActionKind::kDiscrete, num_actions}, config, seed),
      num_actions_(num_actions), config_(config) {
  build_networks(seed, q_, q_target_, [&] { return make_network(spec_, num_actions, config); });
  optimizer_ = make_adam(q_->parameters(), config.learning_rate, config.adam_epsilon, config.weight_decay);
  target_ = FlatParameters(q_target_->parameters(), /*with_grad=*/false);
}

double Dqn::epsilon() const { return epsilon_at(config_, counters_); }

std::vector<float> Dqn::q_values(const Observation& o) { return q_values_of(q_, spec_, num_actions_, device_, o); }

void Dqn::act(const Observation& o, bool explore, Action& action) {
  act_with(q_, spec_, num_actions_, config_, device_, counters_, rng_, acting_, o, explore, action);
}

torch::Tensor Dqn::td_target(const ReplayBatch& b) {
  torch::NoGradGuard no_grad;
  // A batch of terminal transitions only (the co-optimization's return
  // targets) bootstraps nothing: the target network's forward pass, about a
  // quarter of an update, is skipped. The same numbers: the bootstrap term
  // would be 0 times a finite value.
  const torch::Tensor reward = b.reward * config_.reward_scale;  // a new tensor; x 1.0 is exact
  if (!b.bootstrap.any().item<bool>()) return reward;
  {
    const torch::Tensor valid = b.next_valid_actions;
    const torch::Tensor q_next = q_target_->forward(b.next_image, b.next_vector);
    torch::Tensor next_value;
    if (config_.double_dqn) {
      const torch::Tensor q_online = q_->forward(b.next_image, b.next_vector)
                                         .masked_fill(valid.logical_not(), -INFINITY);
      next_value = q_next.gather(1, q_online.argmax(1, true)).squeeze(1);
    } else {
      next_value = std::get<0>(q_next.masked_fill(valid.logical_not(), -INFINITY).max(1));
    }
    // A next state without valid actions (terminal) has value 0, not -inf.
    next_value = torch::where(valid.any(1), next_value, torch::zeros_like(next_value));
    return reward + b.bootstrap * next_value;
  }
}

void Dqn::update() {
  const ReplayBatch b = replay_.sample(config_.batch_size, rng_, device_);
  const torch::Tensor target = td_target(b);
  // Each member regresses on the (shared) target: the mean of the members' losses ([members, B]).
  const torch::Tensor q = q_->forward_members(b.image, b.vector)
                              .gather(2, b.action.view({1, -1, 1}).expand({q_->members(), -1, 1}))
                              .squeeze(2);
  const torch::Tensor targets = target.unsqueeze(0).expand_as(q);
  const torch::Tensor loss = config_.loss == DqnLoss::huber ? torch::smooth_l1_loss(q, targets)
                                                             : torch::mse_loss(q, targets);
  gradient_step(*optimizer_, loss, config_.max_grad_norm);
  last_loss_ = loss.item<double>();
  ++counters_.updates;
  if (counters_.updates % config_.target_update_interval == 0) {
    soft_update(target_, optimizer_->parameters(), std::min(config_.tau, 1.0));
  }
}

Dqn::CheckpointParts Dqn::checkpoint_parts() const {
  return {{{"q", q_.ptr().get()}, {"q_target", q_target_.ptr().get()}}, {{"optimizer", optimizer_.get()}}, {&target_}};
}

std::unique_ptr<Policy> Dqn::policy(const ObservationSpec& observation, int num_actions, const DqnConfig& config,
                                    std::uint64_t seed) {
  return make_network_policy("dqn", "q", observation, num_actions, config, seed, &make_network, &act_with);
}

}  // namespace comorph::rl
