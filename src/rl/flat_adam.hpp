// Parameters kept in one contiguous buffer, and Adam stepping that buffer as a
// whole. Small networks pay LibTorch's fixed cost per operation: torch's Adam
// runs about 8 operations for each parameter tensor, a Polyak update 2, a
// gradient-norm clip 2 or 3, and a TD3 critic has 12 or more tensors. Over one
// flat buffer each of these is a single operation, whatever the number of
// tensors; the arithmetic is the same, element by element. On the CPU
// (float32) each is a plain loop over the buffer, without LibTorch's
// dispatch; elsewhere a tensor operation.
//
// How: each parameter's data becomes a view into the flat buffer (set_data),
// and so does its gradient. Autograd adds a backward pass's gradient into a
// defined .grad in place, so the gradients land in the flat gradient buffer;
// zero_grad() zeroes that buffer rather than resetting the tensors.
//
// A module load (torch::nn::Module::load) gives each parameter new storage,
// which ends the sharing: call rebind() after it (OffPolicyLearner::load does).
// Moving a module to another device does the same: flatten after to().
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <vector>

namespace comorph::rl {

// Whether plain loops over `t`'s floats can stand in for tensor operations:
// CPU, float32, contiguous. At small sizes LibTorch's dispatch costs more than
// the arithmetic (an Adam step is ~8 operations); on other devices the
// operations run as tensors.
bool is_plain_cpu_float(const torch::Tensor& t);

class FlatParameters {
 public:
  FlatParameters() = default;
  // Copies the parameters' values into one buffer on their device and makes
  // each parameter a view of it; with_grad: their gradients too.
  FlatParameters(std::vector<torch::Tensor> parameters, bool with_grad);

  // After the parameters were given other storage (a module load): copies
  // their current values in and makes them views again.
  void rebind();

  const torch::Tensor& data() const { return data_; }
  const torch::Tensor& grad() const { return grad_; }
  std::int64_t numel() const { return data_.defined() ? data_.numel() : 0; }

 private:
  std::vector<torch::Tensor> parameters_;
  torch::Tensor data_, grad_;
  bool with_grad_ = false;
};

// target <- (1 - tau) target + tau online, over whole buffers (same layout).
void soft_update(FlatParameters& target, const FlatParameters& online, double tau);

// Adam (Kingma & Ba 2015) as torch::optim::Adam computes it without AMSGrad,
// over one FlatParameters: one operation per term. weight_decay > 0 makes it
// AdamW (Loshchilov & Hutter 2019) as torch::optim::AdamW: every step first
// shrinks the weights by the factor 1 - learning_rate x weight_decay.
class FlatAdam {
 public:
  struct Options {
    double learning_rate = 1e-3;
    double beta1 = 0.9;
    double beta2 = 0.999;
    double epsilon = 1e-8;
    double weight_decay = 0;  // decoupled (AdamW); 0 = plain Adam
  };
  FlatAdam(std::vector<torch::Tensor> parameters, Options options);

  void zero_grad() { parameters_.grad().zero_(); }
  // Scales the gradient so that its L2 norm is at most max_norm (as
  // torch::nn::utils::clip_grad_norm_ with its 1e-6 guard), without reading
  // the norm back to the host.
  void clip_grad_norm(double max_norm);
  void step();
  // See FlatParameters::rebind.
  void rebind() { parameters_.rebind(); }

  const FlatParameters& parameters() const { return parameters_; }
  std::int64_t steps() const { return steps_; }

  // The moments and the step count, under their own keys; load() refuses a
  // state of another size, naming both.
  void save(torch::serialize::OutputArchive& archive) const;
  void load(torch::serialize::InputArchive& archive);

 private:
  FlatParameters parameters_;
  Options options_;
  torch::Tensor exp_avg_, exp_avg_sq_;
  torch::Tensor denominator_;  // scratch of the tensor path (other devices)
  std::int64_t steps_ = 0;
};

}  // namespace comorph::rl
