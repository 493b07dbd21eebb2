#include "rl/mlp_pass.hpp"

#include <cblas.h>

#include <algorithm>
#include <stdexcept>

#include "rl/flat_adam.hpp"

namespace comorph::rl {

bool MlpPass::supports(const Mlp& net) {
  for (const auto& layer : net->layers())
    if (!is_plain_cpu_float(layer->weight) || !is_plain_cpu_float(layer->bias)) return false;
  return true;
}

MlpPass::MlpPass(const Mlp& shape, std::int64_t batch) : batch_(static_cast<int>(batch)) {
  if (!supports(shape)) throw std::invalid_argument("MlpPass: the network's parameters are not CPU float32");
  for (const auto& layer : shape->layers()) {
    const LayerShape s{static_cast<int>(layer->weight.size(1)), static_cast<int>(layer->weight.size(0))};
    shapes_.push_back(s);
    grads_.emplace_back(static_cast<std::size_t>(batch_) * s.in);
    outputs_.emplace_back(static_cast<std::size_t>(batch_) * s.out);
  }
}

float* MlpPass::forward(const Mlp& net, const float* input) {
  const auto& layers = net->layers();
  if (layers.size() != shapes_.size()) throw std::logic_error("MlpPass: the network has another shape");
  net_ = net;
  input_ = input;
  const float* x = input_;
  for (std::size_t i = 0; i < layers.size(); ++i) {
    const auto [in, out] = shapes_[i];
    float* y = outputs_[i].data();
    // Linear: y = W x + b [out, batch], W [out, in] row-major.
    cblas_sgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, out, batch_, in, 1.0f,
                layers[i]->weight.data_ptr<float>(), in, x, batch_, 0.0f, y, batch_);
    const float* bias = layers[i]->bias.data_ptr<float>();
    const bool relu = i + 1 < layers.size();
    for (int o = 0; o < out; ++o) {
      float* row = y + static_cast<std::ptrdiff_t>(o) * batch_;
      const float b = bias[o];
      if (relu)
        for (int r = 0; r < batch_; ++r) row[r] = std::max(row[r] + b, 0.0f);
      else
        for (int r = 0; r < batch_; ++r) row[r] += b;
    }
    x = y;
  }
  return outputs_.back().data();
}

void MlpPass::backward(const float* output_grad, bool parameter_grads, bool input_grad) {
  const auto& layers = net_->layers();
  const float* g = output_grad;  // d loss / d (output of layer k), [out, batch]
  for (std::size_t k = layers.size(); k-- > 0;) {
    const auto [in, out] = shapes_[k];
    const float* x = k == 0 ? input_ : outputs_[k - 1].data();  // the layer's input, [in, batch]
    if (parameter_grads) {
      // d W = g x^T [out, in]; d bias = the batch sum of g.
      cblas_sgemm(CblasRowMajor, CblasNoTrans, CblasTrans, out, in, batch_, 1.0f, g, batch_, x, batch_, 0.0f,
                  layers[k]->weight.grad().data_ptr<float>(), in);
      float* bias_grad = layers[k]->bias.grad().data_ptr<float>();
      for (int o = 0; o < out; ++o) {
        const float* row = g + static_cast<std::ptrdiff_t>(o) * batch_;
        float sum = 0.0f;
        for (int r = 0; r < batch_; ++r) sum += row[r];
        bias_grad[o] = sum;
      }
    }
    if (k == 0 && !input_grad) break;
    // d loss / d x = W^T g [in, batch]; through the previous layer's ReLU where it was active.
    float* dx = grads_[k].data();
    cblas_sgemm(CblasRowMajor, CblasTrans, CblasNoTrans, in, batch_, out, 1.0f, layers[k]->weight.data_ptr<float>(),
                in, g, batch_, 0.0f, dx, batch_);
    if (k > 0)  // a select, not a branch: the ReLU's pattern is random, and a branch would mispredict half the time
      for (std::size_t i = 0; i < grads_[k].size(); ++i) dx[i] = x[i] > 0.0f ? dx[i] : 0.0f;
    g = dx;
  }
}

const float* MlpRow::forward(const Mlp& net, const float* input) {
  const auto& layers = net->layers();
  std::size_t widest = 0;  // the widest layer output (the input is read in place)
  for (const auto& layer : layers) widest = std::max(widest, static_cast<std::size_t>(layer->weight.size(0)));
  if (from_.size() < widest) {
    from_.resize(widest);
    to_.resize(widest);
  }
  const float* x = input;
  for (std::size_t i = 0; i < layers.size(); ++i) {
    const int in = static_cast<int>(layers[i]->weight.size(1)), out = static_cast<int>(layers[i]->weight.size(0));
    float* y = (i % 2 == 0 ? to_ : from_).data();
    const float* bias = layers[i]->bias.data_ptr<float>();
    std::copy(bias, bias + out, y);
    // addmm's call for [1, in] x W^T: column-major y [out, 1] = W^T' x + y.
    cblas_sgemm(CblasColMajor, CblasTrans, CblasNoTrans, out, 1, in, 1.0f, layers[i]->weight.data_ptr<float>(), in, x,
                in, 1.0f, y, out);
    if (i + 1 < layers.size())
      for (int o = 0; o < out; ++o) y[o] = std::max(y[o], 0.0f);
    x = y;
  }
  return x;
}

}  // namespace comorph::rl
