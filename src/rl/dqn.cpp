#include "rl/dqn.hpp"

#include <cmath>
#include <stdexcept>

namespace comorph::rl {

Dqn::Dqn(const ObservationSpec& observation, int num_actions, const DqnConfig& config,
         std::uint64_t seed)
    : spec_(observation), num_actions_(num_actions), config_(config), device_(config.device),
      replay_(observation, {ActionKind::kDiscrete, num_actions}, config.buffer_size,
              image_storage_from_string(config.image_storage)),
      rng_(seed) {
  if (num_actions < 1) throw std::invalid_argument("Dqn: need at least one action");
  torch::manual_seed(seed);  // network initialisation
  q_ = QNetwork(spec_, num_actions, config.hidden_sizes, config.image_features, config.image_fc_size);
  q_target_ = QNetwork(spec_, num_actions, config.hidden_sizes, config.image_features,
                       config.image_fc_size);
  q_->to(device_);
  q_target_->to(device_);
  copy_parameters(*q_target_, *q_);
  optimizer_ = std::make_unique<torch::optim::Adam>(
      q_->parameters(), torch::optim::AdamOptions(config.learning_rate).eps(config.adam_epsilon));
}

double Dqn::epsilon() const {
  return LinearSchedule{config_.epsilon_start, config_.epsilon_end, config_.epsilon_decay}.at(
      static_cast<double>(counters_.transitions));
}

std::vector<float> Dqn::q_values(const Observation& o) {
  torch::InferenceMode guard;
  torch::Tensor q = q_->forward(image_batch(o, spec_, device_), vector_batch(o, spec_, device_))
                        .to(torch::kCPU);
  return std::vector<float>(q.data_ptr<float>(), q.data_ptr<float>() + num_actions_);
}

void Dqn::act(const Observation& o, bool explore, Action& action) {
  const auto& mask = o.valid_actions;
  if (!mask.empty() && static_cast<int>(mask.size()) != num_actions_)
    throw std::invalid_argument("Dqn::act: valid_actions has " + std::to_string(mask.size()) +
                                " entries, expected " + std::to_string(num_actions_));
  auto valid = [&](int a) { return mask.empty() || mask[a] != 0; };
  int valid_count = 0;
  for (int a = 0; a < num_actions_; ++a) valid_count += valid(a);
  if (valid_count == 0) throw std::invalid_argument("Dqn::act: no valid action in the mask");

  if (explore && std::uniform_real_distribution<double>(0.0, 1.0)(rng_) < epsilon()) {
    // Uniform among the valid actions.
    int k = std::uniform_int_distribution<int>(0, valid_count - 1)(rng_);
    for (int a = 0; a < num_actions_; ++a)
      if (valid(a) && k-- == 0) {
        action.discrete = a;
        return;
      }
  }
  const std::vector<float> q = q_values(o);
  int best = -1;
  for (int a = 0; a < num_actions_; ++a)
    if (valid(a) && (best < 0 || q[a] > q[best])) best = a;
  action.discrete = best;
}

void Dqn::store(const Observation& o, const Action& action, float reward, const Observation& next,
                bool terminated, bool truncated, int steps) {
  const int discount_steps = config_.discount_per == "decision" ? 1 : steps;
  replay_.add(o, action, reward, next, terminated, static_cast<float>(std::pow(config_.gamma, discount_steps)));
  ++counters_.transitions;
  if (terminated || truncated) ++counters_.episodes;
}

int Dqn::updates_due() const {
  if (counters_.transitions < config_.learning_starts) return 0;
  return counters_.transitions % config_.train_frequency == 0 ? config_.gradient_steps : 0;
}

torch::Tensor Dqn::td_target(const ReplayBatch& b) {
  torch::NoGradGuard no_grad;
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
    return b.reward + b.bootstrap * next_value;
  }
}

void Dqn::update() {
  const ReplayBatch b = replay_.sample(config_.batch_size, rng_, device_);
  const torch::Tensor target = td_target(b);
  const torch::Tensor q = q_->forward(b.image, b.vector).gather(1, b.action.unsqueeze(1)).squeeze(1);
  const torch::Tensor loss = config_.loss == "huber" ? torch::smooth_l1_loss(q, target)
                                                     : torch::mse_loss(q, target);
  optimizer_->zero_grad();
  loss.backward();
  if (config_.max_grad_norm > 0) torch::nn::utils::clip_grad_norm_(q_->parameters(), config_.max_grad_norm);
  optimizer_->step();
  last_loss_ = loss.item<double>();
  ++counters_.updates;
  if (counters_.updates % config_.target_update_interval == 0) {
    if (config_.tau >= 1.0) copy_parameters(*q_target_, *q_);
    else soft_update(*q_target_, *q_, config_.tau);
  }
}

void Dqn::save(const std::string& path) const { save_to(path, true); }
void Dqn::save_without_replay(const std::string& path) const { save_to(path, false); }

void Dqn::save_to(const std::string& path, bool with_replay) const {
  torch::serialize::OutputArchive a, nets, target, opt;
  write_common(a, counters_, rng_, "dqn");
  q_->save(nets);
  q_target_->save(target);
  optimizer_->save(opt);
  a.write("q", nets);
  a.write("q_target", target);
  a.write("optimizer", opt);
  write_replay(a, replay_, with_replay);
  save_archive(a, path);
}

void Dqn::save_policy(const std::string& path) const {
  save_policy_file(path, *q_, "q", counters_, rng_, "dqn");
}

void Dqn::load(const std::string& path) {
  torch::serialize::InputArchive a, nets, target, opt;
  a.load_from(path, device_);
  read_common(a, counters_, rng_, "dqn");
  if (read_policy_only(a, "q", *q_)) return;
  a.read("q", nets);
  a.read("q_target", target);
  a.read("optimizer", opt);
  q_->load(nets);
  q_target_->load(target);
  optimizer_->load(opt);
  read_replay(a, replay_);
}

}  // namespace comorph::rl
