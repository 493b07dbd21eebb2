// The forward and backward passes of an Mlp (rl/networks.hpp) written out as
// the ATen operations autograd runs for them, into buffers allocated once for
// a batch size: no autograd graph, no saved-tensor bookkeeping, no tensor
// allocated per pass.
//
// Why: a 64-wide TD3 update is about 100 small operations, and for each one
// autograd builds a graph node, saves its inputs and allocates its output;
// at these sizes that costs more than the arithmetic (docs/rl.md, "Speed").
// The numbers are autograd's bit for bit: the same kernels (addmm for
// Linear, mm for its gradients, sum over the batch for the bias, ReLU's
// threshold_backward) on tensors of the same layouts. A test compares whole
// TD3 trainings both ways.
//
// One pass object serves any Mlp of the shape it was built for (online or
// target network): forward() names the network, backward() follows the last
// forward(). Gradients are written into the parameters' .grad() tensors
// (with FlatAdam, views of its flat gradient buffer), replacing what was
// there, as zero_grad() followed by autograd's accumulation would leave them.
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <vector>

#include "rl/networks.hpp"

namespace comorph::rl {

class MlpPass {
 public:
  MlpPass() = default;
  // Buffers for `batch` rows through networks shaped as `shape` (any Mlp of
  // the same layer sizes), on the device of its parameters.
  MlpPass(const Mlp& shape, std::int64_t batch);

  // The output [batch, out] of `net` for `input` [batch, in] (contiguous).
  // `input` must stay unchanged until backward().
  const torch::Tensor& forward(const Mlp& net, const torch::Tensor& input);

  // From d loss / d output [batch, out]: with parameter_grads, the gradients
  // of the last forward()'s network written into its parameters' .grad();
  // with input_grad, d loss / d input into input_grad().
  void backward(const torch::Tensor& output_grad, bool parameter_grads, bool input_grad);
  const torch::Tensor& input_grad() const { return grads_.front(); }

 private:
  Mlp net_{nullptr};
  torch::Tensor input_;
  std::vector<torch::Tensor> outputs_;  // of each layer, after its ReLU (none on the last)
  std::vector<torch::Tensor> grads_;    // d loss / d (input of layer i)
};

}  // namespace comorph::rl
