// ResNet-18 for one-channel depth images (torch header: include it only where
// torch is needed; callers use scene_classifier.hpp).
//
// Standard ResNet-18 body (He et al. 2016): four stages of two BasicBlocks
// (3x3 conv - BN - ReLU - 3x3 conv - BN, plus identity or 1x1-conv+BN
// shortcut), channels w, 2w, 4w, 8w, stages 2..4 halve the resolution; global
// average pool; linear layer to the class logits. Two changes for tiny depth
// images, as CIFAR ResNets do: the stem is ONE input channel with a 3x3 conv,
// stride 1, and no max-pool (the ImageNet 7x7/2 conv + 3x3/2 pool would shrink
// a 16x16 image to 4x4 before the first block). 16x16 input -> 16, 8, 4, 2.
// Input depths in [0.01, 1] are shifted by -0.5 so they are centred on 0.
#pragma once

#include <torch/torch.h>

namespace comorph::perception {

struct BasicBlockImpl : torch::nn::Module {
  BasicBlockImpl(int in_channels, int out_channels, int stride);
  torch::Tensor forward(const torch::Tensor& x);

  torch::nn::Conv2d conv1{nullptr}, conv2{nullptr};
  torch::nn::BatchNorm2d bn1{nullptr}, bn2{nullptr};
  torch::nn::Sequential shortcut{nullptr};  // 1x1 conv + BN; null for identity
};
TORCH_MODULE(BasicBlock);

struct ResNet18Impl : torch::nn::Module {
  ResNet18Impl(int classes, int width);
  // N x 1 x H x W depths -> N x classes logits.
  torch::Tensor forward(const torch::Tensor& x);

  torch::nn::Conv2d stem{nullptr};
  torch::nn::BatchNorm2d stem_bn{nullptr};
  torch::nn::Sequential layer1{nullptr}, layer2{nullptr}, layer3{nullptr}, layer4{nullptr};
  torch::nn::Linear fc{nullptr};
};
TORCH_MODULE(ResNet18);

}  // namespace comorph::perception
