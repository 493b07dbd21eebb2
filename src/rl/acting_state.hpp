// What an acting rule (DQN's, TD3's and SAC's act_with, shared by a learner
// and its Policy) keeps from one call to the next: the exploration noise's
// state within an episode, and the buffers of its forward pass, sized at
// the first call, so that acting allocates nothing per step.
#pragma once

#include <torch/torch.h>

#include <vector>

#include "rl/mlp_pass.hpp"

namespace comorph::rl {

struct ActingState {
  // TD3's and SAC's coloured exploration noise (step_unit_noise); empty at
  // an episode's start.
  std::vector<float> noise;
  // TD3's actor on one vector observation (CPU): the row pass, and the
  // chosen head's outputs [1, action dims] before and after tanh, which
  // stays LibTorch's (its vectorised tanh rounds otherwise than std::tanh).
  MlpRow actor;
  torch::Tensor head_output, squashed;

  void start_episode() { noise.clear(); }
};

}  // namespace comorph::rl
