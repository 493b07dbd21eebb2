// ResNet-18 modules (resnet.hpp).
#include "perception/resnet.hpp"

namespace comorph::perception {
namespace {

torch::nn::Conv2d conv3x3(int in, int out, int stride) {
  return torch::nn::Conv2d(
      torch::nn::Conv2dOptions(in, out, 3).stride(stride).padding(1).bias(false));
}

torch::nn::Sequential stage(int in, int out, int stride) {
  return torch::nn::Sequential(BasicBlock(in, out, stride), BasicBlock(out, out, 1));
}

}  // namespace

BasicBlockImpl::BasicBlockImpl(int in, int out, int stride) {
  conv1 = register_module("conv1", conv3x3(in, out, stride));
  bn1 = register_module("bn1", torch::nn::BatchNorm2d(out));
  conv2 = register_module("conv2", conv3x3(out, out, 1));
  bn2 = register_module("bn2", torch::nn::BatchNorm2d(out));
  if (stride != 1 || in != out) {
    shortcut = register_module(
        "shortcut",
        torch::nn::Sequential(
            torch::nn::Conv2d(torch::nn::Conv2dOptions(in, out, 1).stride(stride).bias(false)),
            torch::nn::BatchNorm2d(out)));
  }
}

torch::Tensor BasicBlockImpl::forward(const torch::Tensor& x) {
  torch::Tensor y = torch::relu(bn1(conv1(x)));
  y = bn2(conv2(y));
  return torch::relu(y + (shortcut ? shortcut->forward(x) : x));
}

ResNet18Impl::ResNet18Impl(int classes, int width) {
  stem = register_module("stem", conv3x3(1, width, 1));
  stem_bn = register_module("stem_bn", torch::nn::BatchNorm2d(width));
  layer1 = register_module("layer1", stage(width, width, 1));
  layer2 = register_module("layer2", stage(width, 2 * width, 2));
  layer3 = register_module("layer3", stage(2 * width, 4 * width, 2));
  layer4 = register_module("layer4", stage(4 * width, 8 * width, 2));
  fc = register_module("fc", torch::nn::Linear(8 * width, classes));
  // torchvision's initialisation: He-normal convs (fan_out), BN at identity.
  for (auto& m : modules(/*include_self=*/false)) {
    if (auto* conv = m->as<torch::nn::Conv2d>()) {
      torch::nn::init::kaiming_normal_(conv->weight, 0.0, torch::kFanOut, torch::kReLU);
    } else if (auto* bn = m->as<torch::nn::BatchNorm2d>()) {
      torch::nn::init::ones_(bn->weight);
      torch::nn::init::zeros_(bn->bias);
    }
  }
}

torch::Tensor ResNet18Impl::forward(const torch::Tensor& x) {
  torch::Tensor y = torch::relu(stem_bn(stem(x - 0.5)));
  y = layer4->forward(layer3->forward(layer2->forward(layer1->forward(y))));
  y = torch::adaptive_avg_pool2d(y, {1, 1}).flatten(1);
  return fc(y);
}

}  // namespace comorph::perception
