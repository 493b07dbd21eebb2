#include "rl/flat_adam.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace comorph::rl {
bool is_plain_cpu_float(const torch::Tensor& t) {
  return t.device().is_cpu() && t.scalar_type() == torch::kFloat32 && t.is_contiguous();
}

FlatParameters::FlatParameters(std::vector<torch::Tensor> parameters, bool with_grad)
    : parameters_(std::move(parameters)), with_grad_(with_grad) {
  if (parameters_.empty()) throw std::invalid_argument("FlatParameters: no parameters");
  std::int64_t n = 0;
  for (const auto& p : parameters_) n += p.numel();
  const auto options = parameters_.front().options().requires_grad(false);
  data_ = torch::empty({n}, options);
  if (with_grad_) grad_ = torch::zeros({n}, options);
  rebind();
}

void FlatParameters::rebind() {
  torch::NoGradGuard no_grad;
  std::int64_t offset = 0;
  for (auto& p : parameters_) {
    const std::int64_t n = p.numel();
    torch::Tensor slot = data_.narrow(0, offset, n);
    slot.copy_(p.detach().reshape({n}));
    p.set_data(slot.view(p.sizes()));
    if (with_grad_) p.mutable_grad() = grad_.narrow(0, offset, n).view(p.sizes());
    offset += n;
  }
}

void soft_update(FlatParameters& target, const FlatParameters& online, double tau) {
  if (target.numel() != online.numel()) throw std::logic_error("soft_update: buffers differ in size");
  if (is_plain_cpu_float(target.data()) && is_plain_cpu_float(online.data())) {
    float* t = target.data().data_ptr<float>();
    const float* o = online.data().data_ptr<float>();
    const auto keep = static_cast<float>(1.0 - tau), take = static_cast<float>(tau);
    const std::int64_t n = target.numel();  // a constant bound, so that the loop vectorizes
    for (std::int64_t i = 0; i < n; ++i) t[i] = keep * t[i] + take * o[i];
    return;
  }
  torch::NoGradGuard no_grad;
  target.data().mul_(1.0 - tau).add_(online.data(), tau);
}

FlatAdam::FlatAdam(std::vector<torch::Tensor> parameters, Options options)
    : parameters_(std::move(parameters), /*with_grad=*/true), options_(options) {
  exp_avg_ = torch::zeros_like(parameters_.data());
  exp_avg_sq_ = torch::zeros_like(parameters_.data());
  denominator_ = torch::empty_like(parameters_.data());
}

void FlatAdam::clip_grad_norm(double max_norm) {
  const torch::Tensor& g = parameters_.grad();
  if (is_plain_cpu_float(g)) {
    float* d = g.data_ptr<float>();
    const std::int64_t n = g.numel();
    double squares = 0;
    for (std::int64_t i = 0; i < n; ++i) squares += static_cast<double>(d[i]) * d[i];
    const double scale = max_norm / (std::sqrt(squares) + 1e-6);
    if (scale >= 1.0) return;
    const auto f = static_cast<float>(scale);
    for (std::int64_t i = 0; i < n; ++i) d[i] *= f;
    return;
  }
  torch::NoGradGuard no_grad;
  g.mul_((max_norm / (g.norm() + 1e-6)).clamp_max(1.0));
}

void FlatAdam::step() {
  torch::NoGradGuard no_grad;
  ++steps_;
  const double bias_correction1 = 1 - std::pow(options_.beta1, static_cast<double>(steps_));
  const double bias_correction2 = 1 - std::pow(options_.beta2, static_cast<double>(steps_));
  const torch::Tensor& g = parameters_.grad();
  const double decay = 1 - options_.learning_rate * options_.weight_decay;
  if (is_plain_cpu_float(g) && is_plain_cpu_float(parameters_.data())) {
    const float* grad = g.data_ptr<float>();
    float* p = parameters_.data().data_ptr<float>();
    float* m = exp_avg_.data_ptr<float>();
    float* v = exp_avg_sq_.data_ptr<float>();
    const auto b1 = static_cast<float>(options_.beta1), b2 = static_cast<float>(options_.beta2);
    const auto step_size = static_cast<float>(options_.learning_rate / bias_correction1);
    const auto inverse_sqrt_bc2 = static_cast<float>(1.0 / std::sqrt(bias_correction2));
    const auto epsilon = static_cast<float>(options_.epsilon);
    const auto shrink = static_cast<float>(decay);  // 1 without decay: p * 1 is p exactly
    const std::int64_t n = g.numel();
    for (std::int64_t i = 0; i < n; ++i) {
      m[i] = b1 * m[i] + (1.0f - b1) * grad[i];
      v[i] = b2 * v[i] + (1.0f - b2) * grad[i] * grad[i];
      p[i] = shrink * p[i] - step_size * m[i] / (std::sqrt(v[i]) * inverse_sqrt_bc2 + epsilon);
    }
    return;
  }
  if (options_.weight_decay > 0) parameters_.data().mul_(decay);
  exp_avg_.mul_(options_.beta1).add_(g, 1 - options_.beta1);
  exp_avg_sq_.mul_(options_.beta2).addcmul_(g, g, 1 - options_.beta2);
  torch::sqrt_out(denominator_, exp_avg_sq_);
  denominator_.div_(std::sqrt(bias_correction2)).add_(options_.epsilon);
  parameters_.data().addcdiv_(exp_avg_, denominator_, -options_.learning_rate / bias_correction1);
}

void FlatAdam::save(torch::serialize::OutputArchive& archive) const {
  archive.write("steps", torch::tensor({steps_}));
  archive.write("exp_avg", exp_avg_);
  archive.write("exp_avg_sq", exp_avg_sq_);
}

void FlatAdam::load(torch::serialize::InputArchive& archive) {
  torch::Tensor steps, exp_avg, exp_avg_sq;
  if (!archive.try_read("steps", steps) || !archive.try_read("exp_avg", exp_avg) ||
      !archive.try_read("exp_avg_sq", exp_avg_sq))
    throw std::runtime_error(
        "checkpoint: the optimizer state is not a flat Adam's (steps, exp_avg, exp_avg_sq); it was written by an "
        "older comorph, whose checkpoints this one cannot resume");
  if (exp_avg.numel() != exp_avg_.numel() || exp_avg_sq.numel() != exp_avg_sq_.numel())
    throw std::runtime_error("checkpoint: the optimizer state has " + std::to_string(exp_avg.numel()) +
                             " values, these networks " + std::to_string(exp_avg_.numel()));
  torch::NoGradGuard no_grad;
  steps_ = steps.to(torch::kCPU).item<std::int64_t>();
  exp_avg_.copy_(exp_avg);
  exp_avg_sq_.copy_(exp_avg_sq);
}

}  // namespace comorph::rl
