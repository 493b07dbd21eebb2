// Unit tests of the RL core: classic env dynamics, replay buffer, networks,
// DQN masking, terminated vs truncated, YAML hyperparameters.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>
#include <type_traits>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <random>

#include "rl/classic/cartpole.hpp"
#include "rl/classic/pendulum.hpp"
#include "rl/dqn.hpp"
#include "rl/flat_adam.hpp"
#include "rl/n_step.hpp"
#include "rl/networks.hpp"
#include "rl/replay_buffer.hpp"
#include "rl/sac.hpp"
#include "rl/td3.hpp"
#include "rl/train_classic.hpp"

namespace rl = comorph::rl;

namespace {

std::string temp_path(const std::string& name) {
  // The pid keeps concurrent test runs (other build trees) apart.
  return (std::filesystem::temp_directory_path() /
          ("comorph_rl_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

rl::Observation vector_obs(std::vector<float> v, std::vector<std::uint8_t> valid = {}) {
  rl::Observation o;
  o.vector = std::move(v);
  o.valid_actions = std::move(valid);
  return o;
}

}  // namespace

// ---- classic environments ----------------------------------------------------

TEST(Pendulum, HangingDownAtRestCostsPiSquared) {
  rl::PendulumParams p;
  rl::PendulumState s{M_PI, 0.0};
  const double reward = rl::pendulum_step(p, 0.0, s);
  EXPECT_NEAR(reward, -M_PI * M_PI, 1e-12);
  EXPECT_NEAR(s.theta_dot, 15.0 * std::sin(M_PI) * 0.05, 1e-12);
}

TEST(Pendulum, ClipsTorqueAndSpeedAndUsesSemiImplicitEuler) {
  rl::PendulumParams p;
  rl::PendulumState s{M_PI / 2, 7.9};
  // u = 5 is clipped to 2: thdot = 7.9 + (15 + 6) * 0.05 = 8.95 -> clipped to 8.
  const double reward = rl::pendulum_step(p, 5.0, s);
  EXPECT_DOUBLE_EQ(s.theta_dot, 8.0);
  EXPECT_NEAR(s.theta, M_PI / 2 + 8.0 * 0.05, 1e-12);
  EXPECT_NEAR(reward, -((M_PI / 2) * (M_PI / 2) + 0.1 * 7.9 * 7.9 + 0.001 * 4.0), 1e-12);
}

TEST(Pendulum, AngleNormalizeMatchesPythonModulo) {
  EXPECT_NEAR(rl::angle_normalize(M_PI), -M_PI, 1e-12);
  EXPECT_NEAR(rl::angle_normalize(3 * M_PI / 2), -M_PI / 2, 1e-12);
  EXPECT_NEAR(rl::angle_normalize(-3 * M_PI / 2), M_PI / 2, 1e-12);
  EXPECT_NEAR(rl::angle_normalize(0.3), 0.3, 1e-12);
}

TEST(Pendulum, EnvScalesActionObservesAndTruncatesAt200) {
  rl::PendulumEnv env;
  env.seed(3);
  rl::Observation o;
  env.reset(o);
  ASSERT_EQ(o.vector.size(), 3u);
  EXPECT_LE(std::abs(env.state().theta), M_PI);
  EXPECT_LE(std::abs(env.state().theta_dot), 1.0);
  env.set_state({0.0, 0.0});
  rl::Action a;
  a.continuous = {1.0f};  // normalised 1 = 2 N m
  rl::StepResult r = env.step(a, o);
  EXPECT_NEAR(env.state().theta_dot, 3.0 * 2.0 * 0.05, 1e-12);
  EXPECT_NEAR(o.vector[0], std::cos(env.state().theta), 1e-6);
  EXPECT_NEAR(o.vector[1], std::sin(env.state().theta), 1e-6);
  EXPECT_NEAR(r.reward, -0.001 * 4.0, 1e-7);
  int steps = 1;
  while (!r.truncated) {
    EXPECT_FALSE(r.terminated);
    r = env.step(a, o);
    ++steps;
  }
  EXPECT_EQ(steps, 200);
  EXPECT_FALSE(r.terminated);
}

TEST(CartPole, OneStepFromRestMatchesHandComputedEuler) {
  rl::CartPoleParams p;
  rl::CartPoleState s{0, 0, 0, 0};
  EXPECT_FALSE(rl::cartpole_step(p, 1, s));
  // temp = 10/1.1; thetaacc = -temp / (0.5 (4/3 - 0.1/1.1)); xacc = temp - 0.05 thetaacc / 1.1
  const double temp = 10.0 / 1.1;
  const double thetaacc = -temp / (0.5 * (4.0 / 3.0 - 0.1 / 1.1));
  const double xacc = temp - 0.05 * thetaacc / 1.1;
  EXPECT_DOUBLE_EQ(s[0], 0.0);
  EXPECT_NEAR(s[1], 0.02 * xacc, 1e-12);
  EXPECT_NEAR(s[1], 0.195122, 1e-6);
  EXPECT_DOUBLE_EQ(s[2], 0.0);
  EXPECT_NEAR(s[3], -0.292683, 1e-6);
}

TEST(CartPole, TerminatesWhenPoleFallsWithRewardOne) {
  rl::CartPoleEnv env;
  env.seed(1);
  rl::Observation o;
  env.reset(o);
  for (double v : o.vector) EXPECT_LE(std::abs(v), 0.05);
  rl::Action a;
  a.discrete = 1;
  rl::StepResult r;
  int steps = 0;
  do {
    r = env.step(a, o);
    EXPECT_EQ(r.reward, 1.0f);
    ++steps;
  } while (!r.terminated && !r.truncated);
  EXPECT_TRUE(r.terminated);
  EXPECT_FALSE(r.truncated);
  EXPECT_GT(std::abs(env.state()[2]), 12.0 * 2.0 * M_PI / 360.0);
  EXPECT_LT(steps, 50);
}

TEST(CartPole, TruncatesAt500WithoutTermination) {
  rl::CartPoleParams p;
  p.theta_threshold = 1e9;  // never fails
  p.x_threshold = 1e9;
  rl::CartPoleEnv env(p);
  rl::Observation o;
  env.reset(o);
  rl::Action a;
  a.discrete = 0;
  int steps = 0;
  rl::StepResult r;
  do {
    r = env.step(a, o);
    ++steps;
  } while (!r.terminated && !r.truncated);
  EXPECT_EQ(steps, 500);
  EXPECT_TRUE(r.truncated);
  EXPECT_FALSE(r.terminated);
}

// ---- replay buffer -------------------------------------------------------------

TEST(ReplayBuffer, WrapsAroundOverwritingTheOldest) {
  rl::ReplayBuffer buffer({0, 0, 0, 2}, {rl::ActionKind::kContinuous, 1}, 5);
  rl::Action a;
  for (int i = 0; i < 12; ++i) {
    a.continuous = {static_cast<float>(i) / 100};
    buffer.add(vector_obs({float(i), 0}), a, float(i), vector_obs({float(i + 1), 0}), false, 0.9f);
  }
  EXPECT_EQ(buffer.size(), 5);
  EXPECT_EQ(buffer.next_slot(), 12 % 5);
  const rl::ReplayBatch b = buffer.gather(torch::arange(5), torch::kCPU);
  const std::vector<float> expected{10, 11, 7, 8, 9};
  for (int s = 0; s < 5; ++s) {
    EXPECT_EQ(b.reward[s].item<float>(), expected[s]);
    EXPECT_EQ(b.vector[s][0].item<float>(), expected[s]);
    EXPECT_EQ(b.next_vector[s][0].item<float>(), expected[s] + 1);
    EXPECT_FLOAT_EQ(b.action[s][0].item<float>(), expected[s] / 100);
  }
  // Sampling never returns a slot outside the filled range.
  std::mt19937_64 rng(1);
  const rl::ReplayBatch sample = buffer.sample(200, rng, torch::kCPU);
  EXPECT_GE(sample.reward.min().item<float>(), 7);
}

TEST(ReplayBuffer, TerminatedDoesNotBootstrapTruncatedDoes) {
  rl::ReplayBuffer buffer({0, 0, 0, 1}, {rl::ActionKind::kDiscrete, 3}, 8);
  rl::Action a;
  a.discrete = 2;
  buffer.add(vector_obs({0}), a, 1.0f, vector_obs({1}), /*terminated=*/true, 0.99f);
  buffer.add(vector_obs({0}), a, 1.0f, vector_obs({1}), /*terminated=*/false, 0.99f);  // truncated
  buffer.add(vector_obs({0}), a, 1.0f, vector_obs({1}, {0, 1, 0}), false, std::pow(0.99f, 4));
  const rl::ReplayBatch b = buffer.gather(torch::arange(3), torch::kCPU);
  EXPECT_EQ(b.bootstrap[0].item<float>(), 0.0f);
  EXPECT_FLOAT_EQ(b.bootstrap[1].item<float>(), 0.99f);
  EXPECT_FLOAT_EQ(b.bootstrap[2].item<float>(), std::pow(0.99f, 4));
  EXPECT_EQ(b.action[0].item<std::int64_t>(), 2);
  EXPECT_TRUE(b.next_valid_actions[1].all().item<bool>());  // empty mask = all valid
  EXPECT_FALSE(b.next_valid_actions[2][0].item<bool>());
  EXPECT_TRUE(b.next_valid_actions[2][1].item<bool>());
}

TEST(ReplayBuffer, StoresImagesCompactlyAndSavesAndLoads) {
  const rl::ObservationSpec spec{1, 4, 4, 2};
  for (const auto storage : {rl::ImageStorage::kUint8, rl::ImageStorage::kFloat16}) {
    rl::ReplayBuffer buffer(spec, {rl::ActionKind::kContinuous, 2}, 10, storage);
    rl::Observation o, n;
    rl::allocate(spec, o);
    rl::allocate(spec, n);
    rl::Action a;
    a.continuous = {0.5f, -0.5f};
    for (int i = 0; i < 16; ++i) {
      o.image[i] = 0.01f + 0.99f * i / 15.0f;  // depth range [0.01, 1]
      n.image[i] = 1.0f - o.image[i];
    }
    buffer.add(o, a, 1.0f, n, false, 0.99f);
    buffer.add(n, a, 2.0f, o, true, 0.99f);
    const rl::ReplayBatch b = buffer.gather(torch::arange(2), torch::kCPU);
    const double tolerance = storage == rl::ImageStorage::kUint8 ? 0.5 / 255 + 1e-6 : 1e-3;
    for (int i = 0; i < 16; ++i) {
      EXPECT_NEAR(b.image[0].flatten()[i].item<float>(), o.image[i], tolerance);
      EXPECT_NEAR(b.next_image[1].flatten()[i].item<float>(), o.image[i], tolerance);
    }
    const std::string path = temp_path("replay.pt");
    buffer.save(path);
    rl::ReplayBuffer restored(spec, {rl::ActionKind::kContinuous, 2}, 10, storage);
    restored.load(path);
    EXPECT_EQ(restored.size(), 2);
    EXPECT_EQ(restored.next_slot(), 2);
    const rl::ReplayBatch c = restored.gather(torch::arange(2), torch::kCPU);
    EXPECT_TRUE(torch::equal(b.image, c.image));
    EXPECT_TRUE(torch::equal(b.next_image, c.next_image));
    EXPECT_TRUE(torch::equal(b.action, c.action));
    EXPECT_TRUE(torch::equal(b.bootstrap, c.bootstrap));
    rl::ReplayBuffer wrong(spec, {rl::ActionKind::kContinuous, 2}, 11, storage);
    EXPECT_THROW(wrong.load(path), std::runtime_error);
    std::filesystem::remove(path);
  }
}

// ---- networks -------------------------------------------------------------------

TEST(Networks, PaperEncoderShapesForImageSizes) {
  for (int size : {16, 32, 20}) {
    rl::CnnEncoder enc(1, size, size, 9);
    const torch::Tensor out = enc->forward(torch::rand({3, 1, size, size}));
    EXPECT_EQ(out.sizes(), (std::vector<std::int64_t>{3, 9}));
  }
  // conv1 (1->32, 5x5), conv2 (32->64, 5x5), FC 64*4*4 -> 256, FC 256 -> 9 at 16x16.
  rl::CnnEncoder enc(1, 16, 16, 9);
  std::int64_t params = 0;
  for (const auto& p : enc->parameters()) params += p.numel();
  EXPECT_EQ(params, (32 * 25 + 32) + (64 * 32 * 25 + 64) + (1024 * 256 + 256) + (256 * 9 + 9));
}

TEST(Networks, QNetworkImageOnlyIsThePaperNetAndTakesImagePlusVector) {
  rl::QNetwork paper(rl::ObservationSpec{1, 16, 16, 0}, 9, std::vector<int>{}, 256);
  std::int64_t params = 0;
  for (const auto& p : paper->parameters()) params += p.numel();
  EXPECT_EQ(params, (32 * 25 + 32) + (64 * 32 * 25 + 64) + (1024 * 256 + 256) + (256 * 9 + 9));
  rl::QNetwork both(rl::ObservationSpec{1, 16, 16, 5}, 9, std::vector<int>{64}, 16);
  const torch::Tensor q = both->forward(torch::rand({2, 1, 16, 16}), torch::rand({2, 5}));
  EXPECT_EQ(q.sizes(), (std::vector<std::int64_t>{2, 9}));
}

TEST(Networks, QNetworkEnsembleAveragesItsMembersAndKeepsASingleNetworksNames) {
  const rl::ObservationSpec spec{1, 16, 16, 5};
  rl::QNetwork single(spec, 9, std::vector<int>{64}, 16, 32);
  rl::QNetwork ensemble(spec, 9, std::vector<int>{64}, 16, 32, /*members=*/3);
  EXPECT_EQ(ensemble->members(), 3);
  EXPECT_EQ(ensemble->parameters().size(), 3 * single->parameters().size());
  // Member 0 is named as a single network, so a one-member checkpoint reads as before.
  const auto names = single->named_parameters().keys();
  const auto ensemble_names = ensemble->named_parameters().keys();
  for (std::size_t i = 0; i < names.size(); ++i) EXPECT_EQ(ensemble_names[i], names[i]);
  const torch::Tensor image = torch::rand({4, 1, 16, 16}), vector = torch::rand({4, 5});
  const torch::Tensor members = ensemble->forward_members(image, vector);
  EXPECT_EQ(members.sizes(), (std::vector<std::int64_t>{3, 4, 9}));
  EXPECT_TRUE(torch::allclose(ensemble->forward(image, vector), members.mean(0)));
  EXPECT_FALSE(torch::allclose(members[0], members[1]));  // own initial weights
}

TEST(Networks, SharedEncoderGetsNoGradientFromTheActor) {
  rl::ActorCritic nets(rl::ObservationSpec{1, 16, 16, 4}, 5, 5, std::vector<int>{32}, 16, 256, /*share_encoder=*/true);
  const torch::Tensor image = torch::rand({4, 1, 16, 16}), vector = torch::rand({4, 4});
  const torch::Tensor f = nets->critic_features(image, vector);
  EXPECT_EQ(f.size(1), 16 + 4);
  const torch::Tensor a = torch::tanh(nets->actor_head(nets->actor_features(image, vector, f)));
  nets->q1(f.detach(), a).mean().backward();
  for (const auto& p : nets->critic_encoder->parameters()) EXPECT_FALSE(p.grad().defined());
  for (const auto& p : nets->actor->parameters()) EXPECT_TRUE(p.grad().defined());
  // The critic loss does train the encoder.
  (nets->q1(f, a.detach()) + nets->q2(f, a.detach())).mean().backward();
  for (const auto& p : nets->critic_encoder->parameters()) EXPECT_TRUE(p.grad().defined());
  // Not shared: the actor has its own encoder and parameters.
  rl::ActorCritic separate(rl::ObservationSpec{1, 16, 16, 4}, 5, 5, std::vector<int>{32}, 16, 256, /*share_encoder=*/false);
  EXPECT_GT(separate->actor_parameters().size(), separate->actor->parameters().size());
}

TEST(Networks, SoftUpdateIsPolyakAverageOverTheFlatBuffers) {
  rl::Mlp a(3, std::vector<int>{4}, 2), b(3, std::vector<int>{4}, 2);
  rl::copy_parameters(*b, *a);
  EXPECT_TRUE(torch::equal(a->parameters()[0], b->parameters()[0]));
  rl::Mlp c(3, std::vector<int>{4}, 2);
  const torch::Tensor before = b->parameters()[2].clone();
  rl::FlatParameters flat_b(b->parameters(), false), flat_c(c->parameters(), false);
  EXPECT_TRUE(torch::equal(b->parameters()[2], before));  // flattening keeps the values
  rl::soft_update(flat_b, flat_c, 0.25);
  // The module's own parameter moved: it is a view of the buffer.
  EXPECT_TRUE(torch::allclose(b->parameters()[2], 0.75 * before + 0.25 * c->parameters()[2]));
}

// FlatAdam must step exactly as torch's Adam over the same tensors (its
// arithmetic, per element), with clipping as clip_grad_norm_, and survive a
// module load (new storage) through rebind().
TEST(FlatAdam, StepsAsTorchAdamWithClippingAndAfterAModuleLoad) {
  torch::manual_seed(3);
  rl::Mlp reference(5, std::vector<int>{16, 16}, 3), flat(5, std::vector<int>{16, 16}, 3);
  rl::copy_parameters(*flat, *reference);
  torch::optim::Adam torch_adam(reference->parameters(), torch::optim::AdamOptions(3e-3));
  rl::FlatAdam flat_adam(flat->parameters(), {3e-3, 0.9, 0.999, 1e-8});
  const auto step_both = [&](double max_norm) {
    const torch::Tensor x = torch::randn({32, 5}), y = torch::randn({32, 3});
    torch_adam.zero_grad();
    torch::mse_loss(reference->forward(x), y).backward();
    if (max_norm > 0) torch::nn::utils::clip_grad_norm_(reference->parameters(), max_norm);
    torch_adam.step();
    flat_adam.zero_grad();
    torch::mse_loss(flat->forward(x), y).backward();
    if (max_norm > 0) flat_adam.clip_grad_norm(max_norm);
    flat_adam.step();
  };
  const auto expect_same = [&](const char* when) {
    const auto r = reference->parameters(), f = flat->parameters();
    for (std::size_t i = 0; i < r.size(); ++i)
      EXPECT_TRUE(torch::allclose(r[i], f[i], 1e-5, 1e-6)) << when << ", tensor " << i;
  };
  for (int i = 0; i < 20; ++i) step_both(0);
  expect_same("unclipped");
  for (int i = 0; i < 20; ++i) step_both(0.05);  // small enough to clip every step
  expect_same("clipped");
  EXPECT_EQ(flat_adam.steps(), 40);
  // The gradients live in the flat buffer: backward filled it.
  EXPECT_GT(flat_adam.parameters().grad().abs().sum().item<double>(), 0.0);

  // A module load replaces the parameters' storage; after rebind() the
  // optimizer steps the loaded values.
  const std::string path = temp_path("flat_adam_mlp.pt");
  torch::save(reference, path);
  torch::load(flat, path);
  flat_adam.rebind();
  EXPECT_TRUE(torch::equal(flat_adam.parameters().data(), torch::cat([&] {
    std::vector<torch::Tensor> v;
    for (const auto& p : reference->parameters()) v.push_back(p.detach().reshape({-1}));
    return v;
  }()))) << "rebind copies the loaded values into the buffer";
  for (int i = 0; i < 5; ++i) step_both(0);
  expect_same("after a load and rebind");
  std::filesystem::remove(path);

  // The optimizer state round-trips, and a state of another size is refused.
  torch::serialize::OutputArchive out;
  flat_adam.save(out);
  const std::string state_path = temp_path("flat_adam_state.pt");
  out.save_to(state_path);
  torch::serialize::InputArchive in;
  in.load_from(state_path);
  rl::Mlp other(5, std::vector<int>{8}, 3);
  rl::FlatAdam wrong_size(other->parameters(), {});
  EXPECT_THROW(wrong_size.load(in), std::runtime_error);
  rl::Mlp same(5, std::vector<int>{16, 16}, 3);
  rl::FlatAdam restored(same->parameters(), {});
  torch::serialize::InputArchive in2;
  in2.load_from(state_path);
  restored.load(in2);
  EXPECT_EQ(restored.steps(), 45);
  std::filesystem::remove(state_path);
}

// With weight_decay, FlatAdam steps as torch's AdamW (decoupled decay), and
// the decay is real: the same steps without it leave larger weights.
TEST(FlatAdam, WithWeightDecayStepsAsTorchAdamW) {
  torch::manual_seed(5);
  rl::Mlp reference(5, std::vector<int>{16}, 3), flat(5, std::vector<int>{16}, 3), plain(5, std::vector<int>{16}, 3);
  rl::copy_parameters(*flat, *reference);
  rl::copy_parameters(*plain, *reference);
  torch::optim::AdamW torch_adamw(reference->parameters(), torch::optim::AdamWOptions(3e-3).weight_decay(5.0));
  rl::FlatAdam flat_adamw(flat->parameters(), {3e-3, 0.9, 0.999, 1e-8, 5.0});
  rl::FlatAdam flat_adam(plain->parameters(), {3e-3, 0.9, 0.999, 1e-8});
  const auto norm = [](rl::Mlp& m) {
    double s = 0;
    for (const auto& p : m->parameters()) s += p.pow(2).sum().item<double>();
    return std::sqrt(s);
  };
  for (int i = 0; i < 50; ++i) {
    const torch::Tensor x = torch::randn({32, 5}), y = torch::randn({32, 3});
    torch_adamw.zero_grad();
    torch::mse_loss(reference->forward(x), y).backward();
    torch_adamw.step();
    flat_adamw.zero_grad();
    torch::mse_loss(flat->forward(x), y).backward();
    flat_adamw.step();
    flat_adam.zero_grad();
    torch::mse_loss(plain->forward(x), y).backward();
    flat_adam.step();
  }
  const auto r = reference->parameters(), f = flat->parameters();
  for (std::size_t i = 0; i < r.size(); ++i) EXPECT_TRUE(torch::allclose(r[i], f[i], 1e-5, 1e-6)) << "tensor " << i;
  EXPECT_LT(norm(flat), 0.8 * norm(plain)) << "50 steps x 1.5 % decay each shrink the weights";
}

// ---- DQN masking and targets ------------------------------------------------------

TEST(Dqn, ActsOnlyAmongValidActions) {
  rl::DqnConfig c;
  c.hidden_sizes = {16};
  rl::Dqn dqn({0, 0, 0, 3}, 9, c, 7);
  rl::Action a;
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<std::uint8_t> mask(9, 0);
    mask[trial % 9] = 1;
    mask[(trial * 5 + 3) % 9] = 1;
    const rl::Observation o = vector_obs({float(trial % 7), 0.5f, -1.0f}, mask);
    for (bool explore : {true, false}) {
      dqn.act(o, explore, a);
      ASSERT_TRUE(a.discrete >= 0 && a.discrete < 9);
      EXPECT_EQ(mask[a.discrete], 1) << "picked invalid action " << a.discrete;
    }
  }
  // Greedy: the best valid action, even when an invalid one has a higher Q.
  const rl::Observation o = vector_obs({1, 2, 3});
  const std::vector<float> q = dqn.q_values(o);
  const int best = static_cast<int>(std::max_element(q.begin(), q.end()) - q.begin());
  std::vector<std::uint8_t> mask(9, 1);
  mask[best] = 0;
  dqn.act(vector_obs({1, 2, 3}, mask), false, a);
  EXPECT_NE(a.discrete, best);
  int second = -1;
  for (int i = 0; i < 9; ++i)
    if (i != best && (second < 0 || q[i] > q[second])) second = i;
  EXPECT_EQ(a.discrete, second);
  EXPECT_THROW(dqn.act(vector_obs({1, 2, 3}, std::vector<std::uint8_t>(9, 0)), false, a),
               std::invalid_argument);
}

TEST(Dqn, TargetMaximisesOverNextValidActionsAndRespectsTermination) {
  rl::DqnConfig c;
  c.hidden_sizes = {16};
  c.gamma = 0.9;
  rl::Dqn dqn({0, 0, 0, 2}, 4, c, 3);
  rl::Action a;
  a.discrete = 1;
  const rl::Observation s = vector_obs({0.1f, 0.2f});
  const rl::Observation next = vector_obs({0.3f, -0.4f}, {0, 1, 0, 1});
  dqn.store(s, a, 1.0f, next, /*terminated=*/false, /*truncated=*/true);  // truncated: bootstrap
  dqn.store(s, a, 1.0f, next, /*terminated=*/true, false);               // terminal: no bootstrap
  dqn.store(s, a, 1.0f, next, false, false, /*steps=*/3);                 // semi-MDP: gamma^3
  dqn.store(s, a, 2.0f, vector_obs({0.3f, -0.4f}, {0, 0, 0, 0}), true, false);  // no valid next
  const rl::ReplayBatch b = dqn.replay().gather(torch::arange(4), torch::kCPU);
  const torch::Tensor y = dqn.td_target(b);
  torch::Tensor q_next;
  {
    torch::NoGradGuard g;
    q_next = dqn.target_network()->forward({}, b.next_vector[0].unsqueeze(0))[0];
  }
  const float best_valid = std::max(q_next[1].item<float>(), q_next[3].item<float>());
  EXPECT_NEAR(y[0].item<float>(), 1.0f + 0.9f * best_valid, 1e-5);
  EXPECT_EQ(y[1].item<float>(), 1.0f);
  EXPECT_NEAR(y[2].item<float>(), 1.0f + std::pow(0.9f, 3) * best_valid, 1e-5);
  EXPECT_EQ(y[3].item<float>(), 2.0f);
  // A batch of terminal transitions only (the trainer's return targets): their rewards.
  const torch::Tensor y_terminal = dqn.td_target(dqn.replay().gather(torch::tensor({1, 3}, torch::kLong), torch::kCPU));
  EXPECT_EQ(y_terminal[0].item<float>(), 1.0f);
  EXPECT_EQ(y_terminal[1].item<float>(), 2.0f);
  // The masked max differs from the unmasked one when an invalid action is best.
  const float best_any = q_next.max().item<float>();
  if (best_any != best_valid) {
    EXPECT_GT(std::abs(y[0].item<float>() - (1.0f + 0.9f * best_any)), 1e-6);
  }
}

TEST(Dqn, DiscountPerDecisionIgnoresTheSegmentLength) {
  rl::DqnConfig c;
  c.hidden_sizes = {16};
  c.gamma = 0.9;
  c.discount_per = rl::DiscountPer::decision;
  rl::Dqn dqn({0, 0, 0, 2}, 2, c, 3);
  rl::Action a;
  a.discrete = 0;
  const rl::Observation s = vector_obs({0.1f, 0.2f});
  const rl::Observation next = vector_obs({0.3f, -0.4f}, {1, 1});
  dqn.store(s, a, 1.0f, next, false, false, /*steps=*/1);
  dqn.store(s, a, 1.0f, next, false, false, /*steps=*/300);  // a long segment: still gamma once
  const rl::ReplayBatch b = dqn.replay().gather(torch::arange(2), torch::kCPU);
  const torch::Tensor y = dqn.td_target(b);
  torch::Tensor q_next;
  {
    torch::NoGradGuard g;
    q_next = dqn.target_network()->forward({}, b.next_vector[0].unsqueeze(0))[0];
  }
  const float best = q_next.max().item<float>();
  EXPECT_NEAR(y[0].item<float>(), 1.0f + 0.9f * best, 1e-5);
  EXPECT_NEAR(y[1].item<float>(), 1.0f + 0.9f * best, 1e-5);
}

TEST(Dqn, EpsilonScheduleIsLinearThenFlat) {
  rl::DqnConfig c;
  c.hidden_sizes = {8};
  c.epsilon_start = 1.0;
  c.epsilon_end = 0.1;
  c.epsilon_decay = 10;
  rl::Dqn dqn({0, 0, 0, 1}, 2, c, 1);
  rl::Action a;
  a.discrete = 0;
  EXPECT_DOUBLE_EQ(dqn.epsilon(), 1.0);
  for (int i = 0; i < 5; ++i) dqn.store(vector_obs({0}), a, 0, vector_obs({0}), false, false);
  EXPECT_NEAR(dqn.epsilon(), 0.55, 1e-12);
  for (int i = 0; i < 10; ++i) dqn.store(vector_obs({0}), a, 0, vector_obs({0}), false, false);
  EXPECT_NEAR(dqn.epsilon(), 0.1, 1e-12);
}

TEST(Td3, ExplorationNoiseDecaysPerEpisode) {
  rl::Td3Config c;
  c.hidden_sizes = {8};
  c.exploration_noise_start = 0.12;
  c.exploration_noise_end = 0.02;
  c.exploration_noise_decay = 4;
  c.exploration_noise_unit = rl::NoiseDecayUnit::episodes;
  rl::Td3 td3({0, 0, 0, 1}, 1, c, 1);
  rl::Action a;
  a.continuous = {0};
  EXPECT_DOUBLE_EQ(td3.exploration_noise(), 0.12);
  td3.store(vector_obs({0}), a, 0, vector_obs({0}), false, false);
  EXPECT_DOUBLE_EQ(td3.exploration_noise(), 0.12);  // not an episode end
  td3.store(vector_obs({0}), a, 0, vector_obs({0}), false, true);
  td3.store(vector_obs({0}), a, 0, vector_obs({0}), true, false);
  EXPECT_NEAR(td3.exploration_noise(), 0.07, 1e-12);
  for (int i = 0; i < 3; ++i) td3.store(vector_obs({0}), a, 0, vector_obs({0}), true, false);
  EXPECT_NEAR(td3.exploration_noise(), 0.02, 1e-12);
}

// Exploration noise of one policy over an episode of `steps` steps on a fixed
// observation: the action minus the greedy action, per step, dimension 0
// (the action itself during the random warm-up).
template <class Algorithm, class Config>
std::vector<double> exploration_deviations(double correlation, int steps, bool warmup) {
  Config c;
  c.hidden_sizes = {8};
  c.random_action_steps = warmup ? 1000000 : 0;
  if constexpr (std::is_same_v<Config, rl::Td3Config>) c.exploration_noise_start = c.exploration_noise_end = 0.2;
  c.exploration_noise_correlation = correlation;
  const auto policy = Algorithm::policy({0, 0, 0, 1}, 2, c, 7);
  rl::Action greedy, a;
  policy->act(vector_obs({0.3f}), false, greedy);
  std::vector<double> d;
  for (int t = 0; t < steps; ++t) {
    policy->act(vector_obs({0.3f}), true, a);
    d.push_back(warmup ? a.continuous[0] : a.continuous[0] - greedy.continuous[0]);
    policy->count(false, false);
  }
  return d;
}

// Lag-1 correlation and standard deviation of a series.
std::pair<double, double> lag1_and_std(const std::vector<double>& x) {
  double mean = 0;
  for (double v : x) mean += v;
  mean /= static_cast<double>(x.size());
  double var = 0, cov = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    var += (x[i] - mean) * (x[i] - mean);
    if (i > 0) cov += (x[i] - mean) * (x[i - 1] - mean);
  }
  return {cov / var, std::sqrt(var / static_cast<double>(x.size()))};
}

// White noise (correlation 0) is what TD3 always drew; with rho the noise
// keeps its std but follows an AR(1) process with lag-1 correlation rho, and
// the random-action warm-up stays uniform in [-1, 1] (std 1 / sqrt 3).
TEST(Td3, CorrelatedExplorationNoiseKeepsItsStdAndHasTheAskedCorrelation) {
  for (double rho : {0.0, 0.9, 0.98}) {
    // One episode of 20 000 steps.
    const auto [lag1, std] = lag1_and_std(exploration_deviations<rl::Td3, rl::Td3Config>(rho, 20000, false));
    EXPECT_NEAR(lag1, rho, 0.02) << "rho " << rho;
    EXPECT_NEAR(std, 0.2, rho > 0.95 ? 0.03 : 0.01) << "rho " << rho;
    const auto [warm_lag1, warm_std] = lag1_and_std(exploration_deviations<rl::Td3, rl::Td3Config>(rho, 20000, true));
    EXPECT_NEAR(warm_std, 1.0 / std::sqrt(3.0), rho > 0.95 ? 0.05 : 0.02) << "rho " << rho;
    EXPECT_GT(warm_lag1, rho - 0.05) << "rho " << rho;
    EXPECT_LT(warm_lag1, rho + 0.05) << "rho " << rho;
  }
}

// SAC's exploring samples draw their unit noise from the same process: white
// (lag-1 correlation 0) by default, correlated as asked with rho; its random
// warm-up is TD3's (uniform in [-1, 1], correlated with rho).
TEST(Sac, CorrelatedExplorationHasTheAskedCorrelation) {
  for (double rho : {0.0, 0.9, 0.98}) {
    const auto [lag1, std] = lag1_and_std(exploration_deviations<rl::Sac, rl::SacConfig>(rho, 10000, false));
    EXPECT_NEAR(lag1, rho, rho > 0 ? 0.02 : 0.03) << "rho " << rho;
    EXPECT_GT(std, 0.05) << "rho " << rho;  // the initial actor's std, about exp(-1.5)
    const auto [warm_lag1, warm_std] = lag1_and_std(exploration_deviations<rl::Sac, rl::SacConfig>(rho, 10000, true));
    EXPECT_NEAR(warm_std, 1.0 / std::sqrt(3.0), rho > 0.95 ? 0.06 : 0.02) << "rho " << rho;
    EXPECT_NEAR(warm_lag1, rho, 0.05) << "rho " << rho;
  }
}

TEST(Td3, CorrelatedNoiseStartsAfreshEachEpisode) {
  rl::Td3Config c;
  c.hidden_sizes = {8};
  c.random_action_steps = 0;
  c.exploration_noise_correlation = 0.99;
  // Three policies of one seed draw the same numbers. `ended` ends an episode
  // after its 5th step, `fresh` after every step, `running` never: at the 6th
  // step the first two start from a fresh draw, the third continues its process.
  const auto ended = rl::Td3::policy({0, 0, 0, 1}, 2, c, 3);
  const auto fresh = rl::Td3::policy({0, 0, 0, 1}, 2, c, 3);
  const auto running = rl::Td3::policy({0, 0, 0, 1}, 2, c, 3);
  rl::Action x, y, z;
  for (int t = 0; t < 6; ++t) {
    ended->act(vector_obs({0}), true, x);
    fresh->act(vector_obs({0}), true, y);
    running->act(vector_obs({0}), true, z);
    ended->count(false, t == 4);
    fresh->count(true, false);
    running->count(false, false);
  }
  EXPECT_EQ(x.continuous, y.continuous);
  EXPECT_NE(x.continuous, z.continuous);
}

// n-step returns: each transition sums n rewards, discounted, and bootstraps
// from the state n steps on; the episode's end flushes the rest with fewer.
TEST(NStepReturns, SumsNRewardsAndFlushesAtTheEpisodeEnd) {
  struct Out {
    float obs, reward, next;
    bool terminated, truncated;
    int steps;
  };
  for (bool truncate : {false, true}) {
    rl::NStepReturns n_step(3, 0.5);
    std::vector<Out> out;
    auto emit = [&](const rl::Observation& o, const rl::Action& a, float r, const rl::Observation& n, bool term,
                    bool trunc, int steps) {
      EXPECT_EQ(a.continuous[0], o.vector[0] * 10);
      out.push_back({o.vector[0], r, n.vector[0], term, trunc, steps});
    };
    rl::Action a;
    for (int t = 0; t < 5; ++t) {
      a.continuous = {static_cast<float>(t) * 10};
      const bool end = t == 4;
      n_step.add(vector_obs({static_cast<float>(t)}), a, static_cast<float>(t + 1), vector_obs({static_cast<float>(t + 1)}),
                 end && !truncate, end && truncate, emit);
      EXPECT_EQ(out.size(), end ? 5u : static_cast<std::size_t>(std::max(0, t - 1)));
    }
    EXPECT_EQ(n_step.pending(), 0);
    // Rewards 1..5; returns r_t + 0.5 r_t+1 + 0.25 r_t+2.
    const std::vector<Out> want = {{0, 1 + 1.0f + 0.75f, 3, false, false, 3},
                                   {1, 2 + 1.5f + 1.0f, 4, false, false, 3},
                                   {2, 3 + 2.0f + 1.25f, 5, !truncate, truncate, 3},
                                   {3, 4 + 2.5f, 5, !truncate, truncate, 2},
                                   {4, 5, 5, !truncate, truncate, 1}};
    for (std::size_t i = 0; i < want.size(); ++i) {
      EXPECT_EQ(out[i].obs, want[i].obs) << i;
      EXPECT_FLOAT_EQ(out[i].reward, want[i].reward) << i;
      EXPECT_EQ(out[i].next, want[i].next) << i;
      EXPECT_EQ(out[i].terminated, want[i].terminated) << i;
      EXPECT_EQ(out[i].truncated, want[i].truncated) << i;
      EXPECT_EQ(out[i].steps, want[i].steps) << i;
    }
  }
}

TEST(NStepReturns, OneStepPassesTransitionsThrough) {
  rl::NStepReturns n_step(1, 0.99);
  rl::Action a;
  a.continuous = {0.5f};
  int calls = 0;
  n_step.add(vector_obs({1}), a, 2.0f, vector_obs({3}), false, false,
             [&](const rl::Observation& o, const rl::Action&, float r, const rl::Observation& n, bool, bool, int k) {
               ++calls;
               EXPECT_EQ(o.vector[0], 1);
               EXPECT_EQ(r, 2.0f);
               EXPECT_EQ(n.vector[0], 3);
               EXPECT_EQ(k, 1);
             });
  EXPECT_EQ(calls, 1);
  EXPECT_THROW(rl::NStepReturns(0, 0.99), std::invalid_argument);
}

// A small TD3 that updates its actor at every update, from the first transition.
rl::Td3Config small_td3() {
  rl::Td3Config c;
  c.hidden_sizes = {32, 32};
  c.batch_size = 64;
  c.buffer_size = 1000;
  c.learning_starts = 0;
  c.random_action_steps = 0;
  c.policy_delay = 1;
  c.actor_learning_rate = 3e-3;
  return c;
}

// Behaviour cloning: every transition ends with reward 1 whatever the action,
// so the critic learns a flat Q and gives the actor no direction; only the BC term on the demonstrated transitions can move it to
// the demonstrated action (0.7 where x > 0, -0.4 where x < 0). Without it the
// actor stays where the initialisation put it. Non-demonstrated transitions
// with other actions must not pull it.
double bc_error_after_training(double bc_weight) {
  rl::Td3Config c = small_td3();
  c.bc_weight = bc_weight;
  rl::Td3 td3({0, 0, 0, 1}, 1, c, 3);
  rl::Action a;
  for (int i = 0; i < 400; ++i) {
    const float x = static_cast<float>(i % 20) / 10.0f - 0.95f;
    const bool demonstrated = i % 2 == 0;
    a.continuous = {demonstrated ? (x > 0 ? 0.7f : -0.4f) : 0.9f * (i % 3 == 0 ? 1.0f : -1.0f)};
    a.target.clear();
    if (demonstrated) a.target = a.continuous;
    td3.store(vector_obs({x}), a, 1.0f, vector_obs({x}), true, false);
  }
  for (int u = 0; u < 800; ++u) td3.update();
  double error = 0;
  for (float x : {-0.8f, -0.3f, 0.3f, 0.8f}) {
    td3.act(vector_obs({x}), false, a);
    error += std::abs(a.continuous[0] - (x > 0 ? 0.7f : -0.4f));
  }
  return error / 4;
}

TEST(Td3, BehaviourCloningPullsTheActorToTheDemonstratedActions) {
  const double with_bc = bc_error_after_training(2.5);
  const double without = bc_error_after_training(0.0);
  std::printf("mean |pi(x) - demonstrated| after 800 updates: with BC %.3f, without %.3f\n", with_bc, without);
  EXPECT_LT(with_bc, 0.1);
  EXPECT_GT(without, 0.2);
}

// actor_q_weight 0 takes the critic out of the actor's loss: with no
// demonstrations the actor then does not move, while TD3 (weight 1) finds the
// action the reward prefers (one-step episodes, reward -(a - 0.6)^2).
TEST(Td3, ActorQWeightZeroLeavesTheActorToImitationAlone) {
  for (double q_weight : {1.0, 0.0}) {
    rl::Td3Config c = small_td3();
    c.bc_weight = q_weight == 0 ? 1.0 : 0.0;  // with 0: the imitation term alone, but nothing carries a target
    c.actor_q_weight = q_weight;
    rl::Td3 td3({0, 0, 0, 1}, 1, c, 3);
    rl::Action a, before, after;
    td3.act(vector_obs({0.2f}), false, before);
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (int i = 0; i < 400; ++i) {
      a.continuous = {u(rng)};
      td3.store(vector_obs({0.2f}), a, -(a.continuous[0] - 0.6f) * (a.continuous[0] - 0.6f), vector_obs({0.2f}),
                true, false);
    }
    for (int update = 0; update < 1500; ++update) td3.update();
    td3.act(vector_obs({0.2f}), false, after);
    if (q_weight == 0) {
      EXPECT_EQ(after.continuous, before.continuous);
    } else {
      // From about 0 at initialisation to most of the way.
      EXPECT_GT(std::abs(before.continuous[0] - 0.6f), 0.4f);
      EXPECT_LT(std::abs(after.continuous[0] - 0.6f), 0.2f);
    }
  }
}

// TD3's explicit passes (rl/mlp_pass.hpp) compute what autograd computes, up
// to float rounding: two learners of one seed, one forced onto autograd, train
// on the same transitions and end with networks, targets and optimizer states
// that agree to a few parts in 10^5, and losses to 10^-4 relative, update by
// update. A wrong gradient (a transposed product, a sign, the
// ReLU or tanh derivative left out) moves the networks apart by orders of
// magnitude more within the first updates. With and without behaviour cloning
// (decaying, so that its weight reaches 0), clipping, a batch that is not a
// power of two, two layers and one, one actor head and three (a row acting
// through another head than its next state's).
// Every tensor of `a` is close to the one under the same key of `b`, in nested
// archives too; `largest` is the largest absolute difference seen.
void expect_close_archives(torch::serialize::InputArchive& a, torch::serialize::InputArchive& b,
                           const std::string& prefix, int& compared, double& largest) {
  for (const std::string& key : a.keys()) {
    torch::Tensor ta, tb;
    torch::serialize::InputArchive sa, sb;
    if (a.try_read(key, ta)) {
      ASSERT_TRUE(b.try_read(key, tb)) << prefix << key;
      ASSERT_EQ(ta.sizes(), tb.sizes()) << prefix << key;
      if (ta.is_floating_point()) {
        const double difference = (ta - tb).abs().max().item<double>();
        largest = std::max(largest, difference);
        EXPECT_TRUE(torch::allclose(ta, tb, /*rtol=*/1e-4, /*atol=*/1e-5)) << prefix << key << ": " << difference;
      } else {
        EXPECT_TRUE(torch::equal(ta, tb)) << prefix << key;
      }
      ++compared;
    } else if (a.try_read(key, sa)) {
      ASSERT_TRUE(b.try_read(key, sb)) << prefix << key;
      expect_close_archives(sa, sb, prefix + key + "/", compared, largest);
    }
  }
}

struct ExplicitPassCase {
  double bc_weight;
  double max_grad_norm;
  std::vector<int> hidden;
  double actor_q_weight = 1;
  int heads = 0;  // ObservationSpec::head_selector
};

class Td3ExplicitPasses : public ::testing::TestWithParam<ExplicitPassCase> {};

TEST_P(Td3ExplicitPasses, EqualAutogradUpToRounding) {
  rl::Td3Config c;
  c.hidden_sizes = GetParam().hidden;
  c.batch_size = 37;
  c.buffer_size = 500;
  c.learning_starts = 0;
  c.random_action_steps = 0;
  c.bc_weight = GetParam().bc_weight;
  c.bc_decay_updates = 150;
  c.max_grad_norm = GetParam().max_grad_norm;
  c.actor_q_weight = GetParam().actor_q_weight;
  c.actor_learning_rate = c.critic_learning_rate = 3e-3;
  const int heads = GetParam().heads;
  const rl::ObservationSpec spec{0, 0, 0, 3 + heads, heads};
  rl::Td3 explicit_passes(spec, 2, c, 5), autograd(spec, 2, c, 5);
  autograd.force_autograd(true);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const auto observation = [&] {
    std::vector<float> v{u(rng), u(rng), u(rng)};
    if (heads > 0) {
      v.resize(3 + heads, 0.0f);
      v[3 + rng() % heads] = 1.0f;
    }
    return vector_obs(v);
  };
  rl::Action a;
  for (int i = 0; i < 300; ++i) {
    a.continuous = {u(rng), u(rng)};
    a.target.clear();
    if (i % 3 == 0) a.target = {u(rng), u(rng)};
    const rl::Observation o = observation(), next = observation();
    const float reward = u(rng);
    for (rl::Td3* t : {&explicit_passes, &autograd}) t->store(o, a, reward, next, i % 7 == 0, false);
  }
  for (int update = 0; update < 200; ++update) {
    explicit_passes.update();
    autograd.update();
    ASSERT_NEAR(explicit_passes.last_loss(), autograd.last_loss(), 1e-4 * std::abs(autograd.last_loss()) + 1e-7)
        << "update " << update;
  }
  const std::string path_e = temp_path("td3_explicit.pt"), path_a = temp_path("td3_autograd.pt");
  explicit_passes.save_without_replay(path_e);
  autograd.save_without_replay(path_a);
  torch::serialize::InputArchive ae, aa;
  ae.load_from(path_e);
  aa.load_from(path_a);
  int compared = 0;
  double largest = 0;
  expect_close_archives(ae, aa, "", compared, largest);
  EXPECT_GT(compared, 20);
  std::cout << "largest difference after 200 updates: " << largest << "\n";
  std::filesystem::remove(path_e);
  std::filesystem::remove(path_a);
}

INSTANTIATE_TEST_SUITE_P(Cases, Td3ExplicitPasses,
                         ::testing::Values(ExplicitPassCase{0.0, 0.0, {16, 16}}, ExplicitPassCase{2.5, 0.0, {16, 16}},
                                           ExplicitPassCase{2.5, 1.0, {16, 16}}, ExplicitPassCase{0.0, 0.5, {8}},
                                           ExplicitPassCase{2.5, 0.0, {16, 16}, 0.0},
                                           ExplicitPassCase{2.5, 1.0, {16, 16}, 1.0, 3}));

// Actor heads (ObservationSpec::head_selector): a row acts through the head
// its selector chooses, and trains that head only. Trained on head 0's rows
// alone, the actor's output weights and biases of heads 1 and 2 stay as they
// were initialised, bit for bit (their gradient is zero, so Adam does not
// move them), while head 0's move; and act() answers with the chosen head's
// outputs: after training, head 0's action differs from head 1's for one
// state. Both update paths.
TEST(Td3Heads, ARowActsAndLearnsThroughItsHeadOnly) {
  for (bool autograd : {false, true}) {
    rl::Td3Config c;
    c.hidden_sizes = {16};
    c.batch_size = 32;
    c.buffer_size = 500;
    c.learning_starts = 0;
    c.random_action_steps = 0;
    c.policy_delay = 1;
    c.actor_learning_rate = c.critic_learning_rate = 3e-3;
    const int heads = 3, actions = 2;
    rl::Td3 td3({0, 0, 0, 2 + heads, heads}, actions, c, 4);
    td3.force_autograd(autograd);
    const rl::Mlp& actor = td3.networks()->actor;
    const torch::Tensor weight0 = actor->layers().back()->weight.clone(), bias0 = actor->layers().back()->bias.clone();
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    rl::Action a;
    for (int i = 0; i < 200; ++i) {
      const float x = u(rng);
      a.continuous = {u(rng), u(rng)};
      // A bandit: the reward is highest at action (0.7, -0.7).
      const float reward = -std::pow(a.continuous[0] - 0.7f, 2.0f) - std::pow(a.continuous[1] + 0.7f, 2.0f);
      const rl::Observation o = vector_obs({x, 1.0f, 1.0f, 0.0f, 0.0f});  // selector (1, 0, 0): head 0
      td3.store(o, a, reward, o, /*terminated=*/true, false);
    }
    for (int update = 0; update < 300; ++update) td3.update();
    const torch::Tensor weight = actor->layers().back()->weight, bias = actor->layers().back()->bias;
    const auto rows = [&](int head) { return torch::indexing::Slice(head * actions, (head + 1) * actions); };
    EXPECT_FALSE(torch::equal(weight.index({rows(0)}), weight0.index({rows(0)}))) << "autograd " << autograd;
    EXPECT_FALSE(torch::equal(bias.index({rows(0)}), bias0.index({rows(0)}))) << "autograd " << autograd;
    for (int head : {1, 2}) {
      EXPECT_TRUE(torch::equal(weight.index({rows(head)}), weight0.index({rows(head)}))) << "head " << head;
      EXPECT_TRUE(torch::equal(bias.index({rows(head)}), bias0.index({rows(head)}))) << "head " << head;
    }
    rl::Action head0, head1;
    td3.act(vector_obs({0.2f, 1.0f, 1.0f, 0.0f, 0.0f}), /*explore=*/false, head0);
    td3.act(vector_obs({0.2f, 1.0f, 0.0f, 1.0f, 0.0f}), /*explore=*/false, head1);
    EXPECT_GT(head0.continuous[0], 0.4f) << "autograd " << autograd;  // learned towards 0.7
    EXPECT_LT(head0.continuous[1], -0.4f) << "autograd " << autograd;
    EXPECT_GT(std::abs(head0.continuous[0] - head1.continuous[0]), 0.2f) << "autograd " << autograd;
  }
}

// TD3 acts on a vector observation through the row pass (rl::MlpRow) and
// LibTorch's tanh on preallocated tensors, not through the modules' forward:
// the actions must be the modules' bit for bit, or a run's actions (and the
// shipped runs' evaluations) would change with the speed-up. Pendulum's
// sizes, the presets' motion model's, and actor heads (the chosen head's).
TEST(Td3, ActsAsTheActorModulesComputeBitForBit) {
  struct Case {
    int vector, heads, actions;
    std::vector<int> hidden;
  };
  for (const Case& k : {Case{3, 0, 1, {64, 64}}, Case{70, 0, 5, {128, 128}}, Case{70, 9, 5, {128, 128}}}) {
    rl::Td3Config c;
    c.hidden_sizes = k.hidden;
    c.random_action_steps = 0;
    rl::Td3 td3({0, 0, 0, k.vector, k.heads}, k.actions, c, 7);
    rl::Mlp actor = td3.networks()->actor;
    std::mt19937_64 rng(11);
    std::normal_distribution<float> normal(0.0f, 1.0f);
    int differing = 0;
    rl::Action a;
    for (int i = 0; i < 500; ++i) {
      std::vector<float> x(static_cast<std::size_t>(k.vector));
      for (float& v : x) v = normal(rng);
      int head = 0;
      if (k.heads > 0) {
        head = i % k.heads;
        std::fill(x.end() - k.heads, x.end(), 0.0f);
        x[static_cast<std::size_t>(k.vector - k.heads + head)] = 1.0f;
      }
      td3.act(vector_obs(x), /*explore=*/false, a);
      torch::NoGradGuard no_grad;
      const torch::Tensor expected =
          torch::tanh(actor->forward(torch::from_blob(x.data(), {1, k.vector}).clone())
                          .slice(1, head * k.actions, (head + 1) * k.actions));
      for (int j = 0; j < k.actions; ++j) differing += a.continuous[j] != expected[0][j].item<float>();
    }
    EXPECT_EQ(differing, 0) << "vector " << k.vector << ", heads " << k.heads;
  }
}

// sample_into reuses its batch's tensors and returns what sample() returns
// for the same draws, terminated transitions and targets included.
TEST(ReplayBuffer, SampleIntoEqualsSample) {
  rl::ReplayBuffer buffer({0, 0, 0, 2}, {rl::ActionKind::kContinuous, 2}, 50);
  rl::Action a;
  for (int i = 0; i < 40; ++i) {
    a.continuous = {0.1f * i, -0.2f * i};
    a.target.clear();
    if (i % 3 == 0) a.target = {0.5f, -0.5f};
    buffer.add(vector_obs({float(i), 1.0f}), a, 0.25f * i, vector_obs({float(i + 1), 2.0f}), i % 4 == 0, 0.9f);
  }
  std::mt19937_64 rng_a(3), rng_b(3);
  rl::ReplayBatch into;
  for (int round = 0; round < 3; ++round) {
    const rl::ReplayBatch expected = buffer.sample(16, rng_a, torch::kCPU);
    const void* storage = into.vector.defined() ? into.vector.data_ptr() : nullptr;
    buffer.sample_into(into, 16, rng_b, torch::kCPU);
    if (storage) {
      EXPECT_EQ(into.vector.data_ptr(), storage);  // reused, not reallocated
    }
    for (const auto& [e, got] : {std::pair{expected.vector, into.vector}, {expected.next_vector, into.next_vector},
                                 {expected.action, into.action}, {expected.reward, into.reward},
                                 {expected.bootstrap, into.bootstrap}, {expected.target, into.target},
                                 {expected.has_target, into.has_target}})
      EXPECT_TRUE(torch::equal(e, got));
  }
  EXPECT_GT(into.bootstrap.eq(0).sum().item<int>(), 0);  // some drawn transitions were terminated
}

TEST(ReplayBuffer, KeepsBehaviourCloningTargetsThroughSaveAndLoad) {
  rl::ReplayBuffer buffer({0, 0, 0, 1}, {rl::ActionKind::kContinuous, 1}, 4);
  rl::Action a;
  a.continuous = {0.1f};
  for (int i = 0; i < 3; ++i) {
    a.target.clear();
    if (i == 1) a.target = {-0.3f};
    buffer.add(vector_obs({float(i)}), a, 0.0f, vector_obs({0}), false, 0.99f);
  }
  const std::string path = temp_path("replay_demo.pt");
  buffer.save(path);
  rl::ReplayBuffer restored({0, 0, 0, 1}, {rl::ActionKind::kContinuous, 1}, 4);
  restored.load(path);
  const rl::ReplayBatch b = restored.gather(torch::arange(3), torch::kCPU);
  EXPECT_EQ(b.has_target[0].item<float>(), 0.0f);
  EXPECT_EQ(b.has_target[1].item<float>(), 1.0f);
  EXPECT_EQ(b.has_target[2].item<float>(), 0.0f);
  EXPECT_FLOAT_EQ(b.target[1][0].item<float>(), -0.3f);
  EXPECT_FLOAT_EQ(b.action[1][0].item<float>(), 0.1f);  // the executed action stays apart
  std::filesystem::remove(path);
}

// save_policy writes the networks alone; a learner built with another seed
// that loads it acts greedily exactly as the saved one, for each algorithm,
// and the file is much smaller than a checkpoint with a replay buffer.
template <class L, class C>
void expect_policy_round_trip(const C& config, int actions, const std::string& name) {
  L trained({0, 0, 0, 3}, actions, config, 11);
  rl::Action a;
  if (actions == 1) a.continuous = {0.3f}; else a.discrete = 1;
  for (int i = 0; i < 300; ++i) trained.store(vector_obs({0.1f * (i % 7), 0.2f, -0.3f}), a, 1.0f,
                                              vector_obs({0.0f, 0.1f, 0.2f}), i % 5 == 0, false);
  for (int u = 0; u < 20; ++u) trained.update();
  const std::string full = temp_path(name + "_full.pt"), policy = temp_path(name + "_policy.pt");
  trained.save(full);
  trained.save_policy(policy);
  EXPECT_LT(std::filesystem::file_size(policy), std::filesystem::file_size(full) / 2) << name;
  L loaded({0, 0, 0, 3}, actions, config, 99);
  loaded.load(policy);
  rl::Action x, y;
  for (float v : {-1.0f, 0.0f, 0.7f}) {
    trained.act(vector_obs({v, 0.5f, -v}), false, x);
    loaded.act(vector_obs({v, 0.5f, -v}), false, y);
    EXPECT_EQ(x.discrete, y.discrete) << name;
    EXPECT_EQ(x.continuous, y.continuous) << name;
  }
  std::filesystem::remove(full);
  std::filesystem::remove(policy);
}

TEST(Learners, APolicyOnlyFileActsLikeTheLearnerThatSavedIt) {
  auto small = [](auto c) {
    c.hidden_sizes = {16};
    c.learning_starts = 0;
    c.buffer_size = 2000;
    c.batch_size = 16;
    return c;
  };
  rl::Td3Config td3 = small(rl::Td3Config{});
  rl::SacConfig sac = small(rl::SacConfig{});
  td3.random_action_steps = sac.random_action_steps = 0;
  expect_policy_round_trip<rl::Td3>(td3, 1, "td3");
  expect_policy_round_trip<rl::Sac>(sac, 1, "sac");
  expect_policy_round_trip<rl::Dqn>(small(rl::DqnConfig{}), 4, "dqn");
}

// ---- hyperparameter files -----------------------------------------------------------

TEST(Config, EveryPresetLoadsAndUnknownFieldsAreRejected) {
  for (const char* name : {"pendulum_td3", "pendulum_sac", "cartpole_dqn", "robot_td3_paper",
                           "robot_sac_paper", "robot_dqn_paper"}) {
    const std::string path = rl::rl_config_dir() + "/" + name + ".yaml";
    const YAML::Node node = comorph::load_yaml_file(path);
    const std::string algo = std::string(name).find("td3") != std::string::npos   ? "td3"
                             : std::string(name).find("sac") != std::string::npos ? "sac"
                                                                                  : "dqn";
    if (algo == "td3") {
      EXPECT_NO_THROW(rl::Td3Config::from_yaml(node, path)) << path;
    }
    if (algo == "sac") {
      EXPECT_NO_THROW(rl::SacConfig::from_yaml(node, path)) << path;
    }
    if (algo == "dqn") {
      EXPECT_NO_THROW(rl::DqnConfig::from_yaml(node, path)) << path;
    }
  }
  const rl::Td3Config paper =
      rl::Td3Config::from_yaml(comorph::load_yaml_file(rl::rl_config_dir() + "/robot_td3_paper.yaml"), "x");
  EXPECT_DOUBLE_EQ(paper.actor_learning_rate, 5e-5);
  EXPECT_DOUBLE_EQ(paper.tau, 0.05);
  EXPECT_EQ(paper.policy_delay, 3);
  try {
    rl::Td3Config::from_yaml(YAML::Load("gama: 0.9"), "my.yaml");
    FAIL() << "misspelt field accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("gama"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("my.yaml"), std::string::npos);
  }
  EXPECT_THROW(rl::DqnConfig::from_yaml(YAML::Load("loss: l1"), "x"), std::runtime_error);
  EXPECT_THROW(rl::DqnConfig::from_yaml(YAML::Load("discount_per: episode"), "x"), std::runtime_error);
  EXPECT_THROW(rl::SacConfig::from_yaml(YAML::Load("batch_size: abc"), "x"), std::runtime_error);
  EXPECT_THROW(rl::make_learner("dqn", {0, 0, 0, 3}, {rl::ActionKind::kContinuous, 1}, YAML::Node(),
                                "x", 1),
               std::invalid_argument);
}
