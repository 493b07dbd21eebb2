// The forward and backward passes of an Mlp (rl/networks.hpp) on the CPU, as
// BLAS matrix products (cblas_sgemm) and plain loops over float buffers
// allocated once for a batch size: no autograd graph, no tensor per
// operation, no LibTorch dispatch.
//
// Why: a 64-wide TD3 update is about 100 small operations. Through LibTorch
// each one costs 1 to 2 us of dispatch and bookkeeping, more than its
// arithmetic at these sizes (docs/rl.md, "Speed"). Here a layer is one sgemm
// and one loop.
//
// The numbers are autograd's up to float rounding: the same products, with
// sums taken in other orders (a bias gradient's batch sum, a tanh). A test
// compares whole TD3 trainings both ways.
//
// Activations are stored feature-major: a batch of rows is [features,
// batch], row-major (the transpose of a batch tensor). A layer's product is
// then W x with both untransposed, which OpenBLAS runs on its small-matrix
// kernels; the batch-major x W^T takes its packing path at these sizes, as
// does only the hidden layers' weight gradient here.
//
// One pass object serves any Mlp of the shape it was built for (online or
// target network): forward() names the network, backward() follows the last
// forward(). Gradients are written into the parameters' .grad() tensors
// (with FlatAdam, views of its flat gradient buffer), replacing what was
// there, as zero_grad() followed by autograd's accumulation would leave them.
// CPU float32 parameters only (supports()); other devices train on autograd.
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
  // the same layer sizes). Throws unless supports(shape).
  MlpPass(const Mlp& shape, std::int64_t batch);

  // Whether the passes can run `net`: contiguous float32 parameters on the CPU.
  static bool supports(const Mlp& net);

  // The output [out, batch] of `net` for `input` [in, batch] (feature-major).
  // `input` must stay unchanged until backward(); the output may be changed
  // in place (backward() does not read it).
  float* forward(const Mlp& net, const float* input);

  // From d loss / d output [out, batch]: with parameter_grads, the gradients
  // of the last forward()'s network written into its parameters' .grad();
  // with input_grad, d loss / d input into input_grad() [in, batch].
  void backward(const float* output_grad, bool parameter_grads, bool input_grad);
  const float* input_grad() const { return grads_.front().data(); }

 private:
  struct LayerShape {
    int in, out;
  };
  Mlp net_{nullptr};
  int batch_ = 0;
  std::vector<LayerShape> shapes_;
  const float* input_ = nullptr;
  std::vector<std::vector<float>> outputs_;  // of each layer, after its ReLU (none on the last)
  std::vector<std::vector<float>> grads_;    // d loss / d (input of layer i)
};

// One row (one observation) through an Mlp as LibTorch's forward computes it
// on the CPU, bit for bit: per layer the bias copied into the output, then
// the BLAS call at::addmm makes for one row (sgemm with beta 1), then the
// ReLU. Acting runs this once a control step; through LibTorch its seven
// operations cost about 9 us of dispatch at Pendulum's sizes, here about 1 us.
class MlpRow {
 public:
  // The output [out] of `net` (MlpPass::supports) for `input` [in]; valid
  // until the next call. Buffers grow at the first call and stay.
  const float* forward(const Mlp& net, const float* input);

 private:
  std::vector<float> from_, to_;
};

}  // namespace comorph::rl
