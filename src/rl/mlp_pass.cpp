#include "rl/mlp_pass.hpp"

#include <stdexcept>

namespace comorph::rl {

MlpPass::MlpPass(const Mlp& shape, std::int64_t batch) {
  const auto options = shape->layers().front()->weight.options().requires_grad(false);
  for (const auto& layer : shape->layers()) {
    const torch::Tensor& w = layer->weight;  // [out, in]
    grads_.push_back(torch::empty({batch, w.size(1)}, options));
    outputs_.push_back(torch::empty({batch, w.size(0)}, options));
  }
}

const torch::Tensor& MlpPass::forward(const Mlp& net, const torch::Tensor& input) {
  torch::NoGradGuard no_grad;
  const auto& layers = net->layers();
  if (layers.size() != outputs_.size()) throw std::logic_error("MlpPass: the network has another shape");
  net_ = net;
  input_ = input;
  const torch::Tensor* x = &input_;
  for (std::size_t i = 0; i < layers.size(); ++i) {
    // Linear as torch::nn::Linear computes it on a 2-D input: bias + x W^T.
    at::addmm_out(outputs_[i], layers[i]->bias, *x, layers[i]->weight.t());
    if (i + 1 < layers.size()) outputs_[i].relu_();
    x = &outputs_[i];
  }
  return outputs_.back();
}

void MlpPass::backward(const torch::Tensor& output_grad, bool parameter_grads, bool input_grad) {
  torch::NoGradGuard no_grad;
  const auto& layers = net_->layers();
  const torch::Tensor* g = &output_grad;  // d loss / d (output of layer i)
  for (std::size_t k = layers.size(); k-- > 0;) {
    const torch::Tensor& w = layers[k]->weight;
    const torch::Tensor& x = k == 0 ? input_ : outputs_[k - 1];
    if (parameter_grads) {
      // addmm's backward: d W = g^T x (as autograd takes it for the
      // column-major W^T), d bias = the batch sum of g.
      torch::Tensor weight_grad = w.grad(), bias_grad = layers[k]->bias.grad();  // handles to the same storage
      at::mm_out(weight_grad, g->t(), x);
      at::sum_out(bias_grad, *g, {0});
    }
    if (k == 0 && !input_grad) break;
    at::mm_out(grads_[k], *g, w);  // d loss / d x = g W
    if (k > 0) at::threshold_backward_out(grads_[k], grads_[k], x, 0);  // ReLU's backward, from its output
    g = &grads_[k];
  }
}

}  // namespace comorph::rl
