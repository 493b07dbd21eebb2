// Network building blocks shared by DQN, TD3 and SAC.
//
// - CnnEncoder: the paper's image encoder (Sec. III, Fig. 2): conv 5x5, 32
//   channels, pad 2 - ReLU - maxpool 2 - conv 5x5, 64 channels, pad 2 - ReLU -
//   maxpool 2 - FC fc_size - ReLU - FC output_size. Image size is a parameter.
// - Mlp: Linear-ReLU-...-Linear (no activation on the output).
// - ObservationEncoder: turns an observation (optional image + optional
//   vector) into one feature vector: the CnnEncoder's output (if there is an
//   image) concatenated with the vector (if there is one). Without an image it
//   has no parameters and just passes the vector through.
// - QNetwork: the DQN's Q(s, .) over n discrete actions. With an image and no
//   vector and no hidden layers it is exactly the paper's configuration model
//   (the CnnEncoder whose last FC has n outputs).
//
// Target networks are built as a second instance of the same architecture and
// started with copy_parameters (parameters in registration order), which
// avoids Cloneable boilerplate; the learners then average them in with one
// soft_update over flat buffers (rl/flat_adam.hpp).
#pragma once

#include <torch/torch.h>

#include <vector>

#include "rl/env.hpp"

namespace comorph::rl {

class CnnEncoderImpl : public torch::nn::Module {
 public:
  CnnEncoderImpl(int channels, int height, int width, int output_size, int fc_size = 256);
  torch::Tensor forward(const torch::Tensor& image);  // [B, C, H, W] -> [B, output_size]
  int output_size() const { return output_size_; }
  // Multiply-adds x 2 of one forward pass for one sample (benchmarks).
  double forward_flops() const;

 private:
  torch::nn::Conv2d conv1_{nullptr}, conv2_{nullptr};
  torch::nn::Linear fc1_{nullptr}, fc2_{nullptr};
  int channels_, height_, width_, fc_size_, output_size_;
};
TORCH_MODULE(CnnEncoder);

class MlpImpl : public torch::nn::Module {
 public:
  MlpImpl(int input_size, const std::vector<int>& hidden_sizes, int output_size);
  torch::Tensor forward(torch::Tensor x);
  double forward_flops() const;  // per sample
  const std::vector<torch::nn::Linear>& layers() const { return layers_; }

 private:
  std::vector<torch::nn::Linear> layers_;
};
TORCH_MODULE(Mlp);

class ObservationEncoderImpl : public torch::nn::Module {
 public:
  // image_features: size of the CNN's output when the observation has an image.
  ObservationEncoderImpl(const ObservationSpec& spec, int image_features, int fc_size = 256);
  // image [B, C, H, W] and vector [B, V]; either may be undefined when the
  // spec has none.
  torch::Tensor forward(const torch::Tensor& image, const torch::Tensor& vector);
  int output_size() const { return output_size_; }
  double forward_flops() const;

 private:
  ObservationSpec spec_;
  CnnEncoder cnn_{nullptr};
  int output_size_;
};
TORCH_MODULE(ObservationEncoder);

class QNetworkImpl : public torch::nn::Module {
 public:
  // members > 1: an ensemble of that many networks of this architecture
  // (member 0 registered as a single network is, so its checkpoints read alike).
  QNetworkImpl(const ObservationSpec& spec, int num_actions, const std::vector<int>& hidden_sizes,
               int image_features, int fc_size = 256, int members = 1);
  torch::Tensor forward(const torch::Tensor& image, const torch::Tensor& vector);  // [B, n], the members' mean
  torch::Tensor forward_members(const torch::Tensor& image, const torch::Tensor& vector);  // [members, B, n]
  int members() const { return static_cast<int>(encoders_.size()); }

 private:
  torch::Tensor member_forward(std::size_t m, const torch::Tensor& image, const torch::Tensor& vector);
  std::vector<ObservationEncoder> encoders_;
  std::vector<Mlp> heads_;  // empty modules for the paper's image-only network
};
TORCH_MODULE(QNetwork);

// The networks of an actor-critic learner (TD3, SAC): twin critics
// Q1, Q2(s, a) and an actor pi(s). The critics share one ObservationEncoder
// (so the convolution runs once per batch for both) and take the action at
// their first FC layer, concatenated with the encoder's features. With
// share_encoder the actor reads the critic encoder's features detached (the
// encoder learns only through the critic loss, as in SAC-AE/DrQ); otherwise
// the actor has its own encoder, trained through the actor loss.
class ActorCriticImpl : public torch::nn::Module {
 public:
  ActorCriticImpl(const ObservationSpec& spec, int action_dims, int actor_outputs,
                  const std::vector<int>& hidden_sizes, int image_features, int fc_size,
                  bool share_encoder);
  torch::Tensor critic_features(const torch::Tensor& image, const torch::Tensor& vector);
  // Features for the actor; `critic_features` (may be undefined) is reused,
  // detached, when the encoder is shared.
  torch::Tensor actor_features(const torch::Tensor& image, const torch::Tensor& vector,
                               const torch::Tensor& critic_features);
  torch::Tensor q1(const torch::Tensor& features, const torch::Tensor& action);
  torch::Tensor q2(const torch::Tensor& features, const torch::Tensor& action);
  torch::Tensor actor_head(const torch::Tensor& features) { return actor->forward(features); }
  std::vector<torch::Tensor> critic_parameters() const;  // encoder + Q1 + Q2
  std::vector<torch::Tensor> actor_parameters() const;   // actor (+ its own encoder)
  bool shares_encoder() const { return actor_encoder.is_empty(); }

  ObservationEncoder critic_encoder{nullptr}, actor_encoder{nullptr};
  Mlp actor{nullptr}, critic1{nullptr}, critic2{nullptr};
};
TORCH_MODULE(ActorCritic);

// dst <- src, parameter by parameter (same architecture).
void copy_parameters(torch::nn::Module& dst, const torch::nn::Module& src);
// dst <- (1 - weight) dst + weight src, parameter by parameter (same
// architecture): weight 1 / k for the k-th of k snapshots keeps their mean.
void blend_parameters(torch::nn::Module& dst, const torch::nn::Module& src, double weight);

// A batch of one observation as tensors on `device` ([1, C, H, W] and [1, V];
// undefined where the spec has none).
torch::Tensor image_batch(const Observation& observation, const ObservationSpec& spec,
                          const torch::Device& device);
torch::Tensor vector_batch(const Observation& observation, const ObservationSpec& spec,
                           const torch::Device& device);
// Throws unless the observation's vector has the spec's size.
void check_vector_size(const Observation& observation, const ObservationSpec& spec);

}  // namespace comorph::rl
