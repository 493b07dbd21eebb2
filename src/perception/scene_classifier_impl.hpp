// Inside of SceneClassifier (torch): for training.cpp and scene_classifier.cpp.
#pragma once

#include <torch/torch.h>

#include "perception/resnet.hpp"
#include "perception/scene_classifier.hpp"

namespace comorph::perception {

struct SceneClassifier::Impl {
  ClassifierParams params;
  torch::Device device;
  ResNet18 net;

  Impl(const ClassifierParams& p, torch::Device d)
      : params(p), device(d), net(ResNet18(p.classes, p.width)) {
    net->to(device);
  }
};

// torch::Device from a params string; throws std::invalid_argument naming it.
torch::Device parse_device(const std::string& device);

}  // namespace comorph::perception
