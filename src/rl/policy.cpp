#include "rl/policy.hpp"

#include <torch/torch.h>

#include <algorithm>
#include <stdexcept>

#include "rl/networks.hpp"

namespace comorph::rl {

void Policy::sync_from(const Learner& learner) { copy_parameters(acting_module(), learner.acting_networks()); }

void Policy::blend_from(const Learner& learner, double weight) {
  blend_parameters(acting_module(), learner.acting_networks(), weight);
}

void acting_weights(const Learner& learner, std::vector<float>& weights) {
  const auto parameters = learner.acting_networks().parameters();
  std::size_t size = 0;
  for (const torch::Tensor& p : parameters) size += static_cast<std::size_t>(p.numel());
  weights.resize(size);
  std::size_t at = 0;
  for (const torch::Tensor& p : parameters) {
    const torch::Tensor c = p.detach().to(torch::kCPU).contiguous();
    std::copy(c.data_ptr<float>(), c.data_ptr<float>() + c.numel(), weights.data() + at);
    at += static_cast<std::size_t>(c.numel());
  }
}

void Policy::load_weights(const std::vector<float>& weights) {
  torch::NoGradGuard no_grad;
  std::size_t at = 0;
  for (torch::Tensor& p : acting_module().parameters()) {
    const auto n = static_cast<std::size_t>(p.numel());
    if (at + n > weights.size()) throw std::logic_error("Policy::load_weights: fewer weights than parameters");
    p.copy_(torch::from_blob(const_cast<float*>(weights.data() + at), p.sizes(), torch::kFloat32));
    at += n;
  }
  if (at != weights.size()) throw std::logic_error("Policy::load_weights: more weights than parameters");
}

void Policy::save(const std::string& path) const {
  save_policy_file(path, acting_module(), key_, counters_, rng_, algorithm_);
}

void Policy::load(const std::string& path) {
  torch::serialize::InputArchive a, nets;
  a.load_from(path, torch::Device(device_));
  read_common(a, counters_, rng_, algorithm_);
  a.read(key_, nets);  // a policy file's networks, or a full checkpoint's online networks
  acting_module().load(nets);
}

}  // namespace comorph::rl
