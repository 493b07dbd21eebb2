#include "rl/policy.hpp"

#include <torch/torch.h>

#include "rl/networks.hpp"

namespace comorph::rl {

void Policy::sync_from(const Learner& learner) { copy_parameters(acting_module(), learner.acting_networks()); }

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
