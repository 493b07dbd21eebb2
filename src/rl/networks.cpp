#include "rl/networks.hpp"

#include <stdexcept>
#include <string>

namespace comorph::rl {

namespace {
int pooled(int size) { return (size / 2) / 2; }  // two floor-halving max pools
}  // namespace

CnnEncoderImpl::CnnEncoderImpl(int channels, int height, int width, int output_size, int fc_size)
    : channels_(channels), height_(height), width_(width), fc_size_(fc_size),
      output_size_(output_size) {
  if (channels <= 0 || height < 4 || width < 4 || output_size <= 0 || fc_size <= 0)
    throw std::invalid_argument("CnnEncoder: need channels > 0, height and width >= 4, got " +
                                std::to_string(channels) + "x" + std::to_string(height) + "x" +
                                std::to_string(width));
  namespace nn = torch::nn;
  conv1_ = register_module("conv1", nn::Conv2d(nn::Conv2dOptions(channels, 32, 5).padding(2)));
  conv2_ = register_module("conv2", nn::Conv2d(nn::Conv2dOptions(32, 64, 5).padding(2)));
  fc1_ = register_module("fc1", nn::Linear(64 * pooled(height) * pooled(width), fc_size));
  fc2_ = register_module("fc2", nn::Linear(fc_size, output_size));
}

torch::Tensor CnnEncoderImpl::forward(const torch::Tensor& image) {
  torch::Tensor x = torch::max_pool2d(torch::relu(conv1_->forward(image)), 2);
  x = torch::max_pool2d(torch::relu(conv2_->forward(x)), 2);
  x = torch::relu(fc1_->forward(x.flatten(1)));
  return fc2_->forward(x);
}

double CnnEncoderImpl::forward_flops() const {
  const double h2 = height_ / 2, w2 = width_ / 2;
  const double conv1 = 2.0 * height_ * width_ * 32 * channels_ * 25;
  const double conv2 = 2.0 * h2 * w2 * 64 * 32 * 25;
  const double fc1 = 2.0 * 64 * pooled(height_) * pooled(width_) * fc_size_;
  const double fc2 = 2.0 * fc_size_ * output_size_;
  return conv1 + conv2 + fc1 + fc2;
}

MlpImpl::MlpImpl(int input_size, const std::vector<int>& hidden_sizes, int output_size) {
  int in = input_size;
  std::vector<int> sizes = hidden_sizes;
  sizes.push_back(output_size);
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    if (sizes[i] <= 0) throw std::invalid_argument("Mlp: layer sizes must be > 0");
    layers_.push_back(register_module("fc" + std::to_string(i), torch::nn::Linear(in, sizes[i])));
    in = sizes[i];
  }
}

torch::Tensor MlpImpl::forward(torch::Tensor x) {
  for (std::size_t i = 0; i < layers_.size(); ++i) {
    x = layers_[i]->forward(x);
    if (i + 1 < layers_.size()) x = torch::relu(x);
  }
  return x;
}

double MlpImpl::forward_flops() const {
  double f = 0;
  for (const auto& l : layers_) f += 2.0 * l->weight.size(0) * l->weight.size(1);
  return f;
}

ObservationEncoderImpl::ObservationEncoderImpl(const ObservationSpec& spec, int image_features,
                                               int fc_size)
    : spec_(spec), output_size_(spec.vector_size) {
  if (!spec.has_image() && !spec.has_vector())
    throw std::invalid_argument("ObservationEncoder: observation has neither image nor vector");
  if (spec.has_image()) {
    cnn_ = register_module("cnn", CnnEncoder(spec.image_channels, spec.image_height,
                                             spec.image_width, image_features, fc_size));
    output_size_ += image_features;
  }
}

torch::Tensor ObservationEncoderImpl::forward(const torch::Tensor& image, const torch::Tensor& vector) {
  if (!spec_.has_image()) return vector;
  torch::Tensor f = cnn_->forward(image);
  return spec_.has_vector() ? torch::cat({f, vector}, 1) : f;
}

double ObservationEncoderImpl::forward_flops() const {
  return cnn_.is_empty() ? 0.0 : cnn_->forward_flops();
}

QNetworkImpl::QNetworkImpl(const ObservationSpec& spec, int num_actions, const std::vector<int>& hidden_sizes,
                           int image_features, int fc_size, int members) {
  if (members < 1) throw std::invalid_argument("QNetwork: members must be >= 1, got " + std::to_string(members));
  const bool paper_image_net = spec.has_image() && !spec.has_vector() && hidden_sizes.empty();
  for (int m = 0; m < members; ++m) {
    const std::string prefix = m == 0 ? "" : "member" + std::to_string(m) + "_";
    encoders_.push_back(register_module(
        prefix + "encoder", ObservationEncoder(spec, paper_image_net ? num_actions : image_features, fc_size)));
    heads_.push_back(paper_image_net ? Mlp{nullptr}
                                     : register_module(prefix + "head", Mlp(encoders_.back()->output_size(),
                                                                             hidden_sizes, num_actions)));
  }
}

torch::Tensor QNetworkImpl::member_forward(std::size_t m, const torch::Tensor& image, const torch::Tensor& vector) {
  torch::Tensor f = encoders_[m]->forward(image, vector);
  return heads_[m].is_empty() ? f : heads_[m]->forward(f);
}

torch::Tensor QNetworkImpl::forward_members(const torch::Tensor& image, const torch::Tensor& vector) {
  std::vector<torch::Tensor> q;
  q.reserve(encoders_.size());
  for (std::size_t m = 0; m < encoders_.size(); ++m) q.push_back(member_forward(m, image, vector));
  return torch::stack(q);
}

torch::Tensor QNetworkImpl::forward(const torch::Tensor& image, const torch::Tensor& vector) {
  return encoders_.size() == 1 ? member_forward(0, image, vector) : forward_members(image, vector).mean(0);
}

void copy_parameters(torch::nn::Module& dst, const torch::nn::Module& src) {
  torch::NoGradGuard no_grad;
  auto d = dst.parameters();
  const auto s = src.parameters();
  if (d.size() != s.size()) throw std::logic_error("copy_parameters: architectures differ");
  for (std::size_t i = 0; i < d.size(); ++i) d[i].copy_(s[i]);
}

void blend_parameters(torch::nn::Module& dst, const torch::nn::Module& src, double weight) {
  torch::NoGradGuard no_grad;
  auto d = dst.parameters();
  const auto s = src.parameters();
  if (d.size() != s.size()) throw std::logic_error("blend_parameters: architectures differ");
  for (std::size_t i = 0; i < d.size(); ++i) d[i].mul_(1.0 - weight).add_(s[i], weight);
}

torch::Tensor image_batch(const Observation& o, const ObservationSpec& spec,
                          const torch::Device& device) {
  if (!spec.has_image()) return {};
  if (static_cast<int>(o.image.size()) != spec.image_size())
    throw std::invalid_argument("observation image has " + std::to_string(o.image.size()) +
                                " values, expected " + std::to_string(spec.image_size()));
  return torch::from_blob(const_cast<float*>(o.image.data()),
                          {1, spec.image_channels, spec.image_height, spec.image_width},
                          torch::kFloat32)
      .to(device);
}

void check_vector_size(const Observation& o, const ObservationSpec& spec) {
  if (static_cast<int>(o.vector.size()) != spec.vector_size)
    throw std::invalid_argument("observation vector has " + std::to_string(o.vector.size()) +
                                " values, expected " + std::to_string(spec.vector_size));
}

torch::Tensor vector_batch(const Observation& o, const ObservationSpec& spec,
                           const torch::Device& device) {
  if (!spec.has_vector()) return {};
  check_vector_size(o, spec);
  return torch::from_blob(const_cast<float*>(o.vector.data()), {1, spec.vector_size},
                          torch::kFloat32)
      .to(device);
}

}  // namespace comorph::rl

namespace comorph::rl {

ActorCriticImpl::ActorCriticImpl(const ObservationSpec& spec, int action_dims, int actor_outputs,
                                 const std::vector<int>& hidden_sizes, int image_features,
                                 int fc_size, bool share_encoder) {
  critic_encoder = register_module("critic_encoder", ObservationEncoder(spec, image_features, fc_size));
  if (!share_encoder && spec.has_image())
    actor_encoder = register_module("actor_encoder", ObservationEncoder(spec, image_features, fc_size));
  const int features = critic_encoder->output_size();
  actor = register_module("actor", Mlp(features, hidden_sizes, actor_outputs));
  critic1 = register_module("critic1", Mlp(features + action_dims, hidden_sizes, 1));
  critic2 = register_module("critic2", Mlp(features + action_dims, hidden_sizes, 1));
}

torch::Tensor ActorCriticImpl::critic_features(const torch::Tensor& image, const torch::Tensor& vector) {
  return critic_encoder->forward(image, vector);
}

torch::Tensor ActorCriticImpl::actor_features(const torch::Tensor& image, const torch::Tensor& vector,
                                              const torch::Tensor& critic_features) {
  if (!actor_encoder.is_empty()) return actor_encoder->forward(image, vector);
  if (critic_features.defined()) return critic_features.detach();
  return critic_encoder->forward(image, vector).detach();
}

torch::Tensor ActorCriticImpl::q1(const torch::Tensor& features, const torch::Tensor& action) {
  return critic1->forward(torch::cat({features, action}, 1)).squeeze(1);
}

torch::Tensor ActorCriticImpl::q2(const torch::Tensor& features, const torch::Tensor& action) {
  return critic2->forward(torch::cat({features, action}, 1)).squeeze(1);
}

std::vector<torch::Tensor> ActorCriticImpl::critic_parameters() const {
  std::vector<torch::Tensor> p = critic_encoder->parameters();
  for (const auto& t : critic1->parameters()) p.push_back(t);
  for (const auto& t : critic2->parameters()) p.push_back(t);
  return p;
}

std::vector<torch::Tensor> ActorCriticImpl::actor_parameters() const {
  std::vector<torch::Tensor> p = actor->parameters();
  if (!actor_encoder.is_empty())
    for (const auto& t : actor_encoder->parameters()) p.push_back(t);
  return p;
}

}  // namespace comorph::rl
