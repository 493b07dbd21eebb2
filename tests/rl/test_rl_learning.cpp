// Learning, determinism and checkpoint tests of DQN, TD3 and SAC.
//
// Learning tests use short runs whose thresholds leave a margin above what
// the untrained (or broken) learner gets; each test also checks that the
// untrained learner fails the same threshold, so that the test can fail.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <filesystem>
#include <numeric>
#include <random>

#include "rl/classic/cartpole.hpp"
#include "rl/classic/pendulum.hpp"
#include "rl/dqn.hpp"
#include "rl/learner.hpp"
#include "rl/sac.hpp"
#include "rl/td3.hpp"
#include "rl/train_classic.hpp"

namespace rl = comorph::rl;

namespace {

struct SingleThread {
  SingleThread() { rl::set_torch_threads(1, 1); }
} single_thread;

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("comorph_rl_" + name)).string();
}

double mean(const std::vector<double>& v) {
  return std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

// A one-step task with an image and a vector: a bright 3x3 spot sits in one
// of `actions` horizontal positions of a 1 x 12 x 12 depth image (background
// 0.01, the paper's range). Discrete: pick the spot's position (reward 1,
// else 0) among the valid actions, which always include the right one.
// Continuous: output a = (spot position scaled to [-1, 1]) + 0.5 * vector[0];
// reward -|a - target|. Every step terminates the episode.
class SpotEnv final : public rl::Env {
 public:
  SpotEnv(bool discrete, int positions) : discrete_(discrete), positions_(positions) {}
  std::string name() const override { return "Spot"; }
  rl::ObservationSpec observation_spec() const override { return {1, 12, 12, discrete_ ? 0 : 2}; }
  rl::ActionSpec action_spec() const override {
    return discrete_ ? rl::ActionSpec{rl::ActionKind::kDiscrete, positions_}
                     : rl::ActionSpec{rl::ActionKind::kContinuous, 1};
  }
  void seed(std::uint64_t seed) override { rng_.seed(seed); }
  void reset(rl::Observation& o) override {
    spot_ = std::uniform_int_distribution<int>(0, positions_ - 1)(rng_);
    offset_ = std::uniform_real_distribution<float>(-1.0f, 1.0f)(rng_);
    o.image.assign(144, 0.01f);
    const int x0 = spot_ * (12 - 3) / (positions_ - 1);
    for (int y = 4; y < 7; ++y)
      for (int x = x0; x < x0 + 3; ++x) o.image[y * 12 + x] = 1.0f;
    if (discrete_) {
      o.vector.clear();
      o.valid_actions.assign(positions_, 0);
      for (auto& v : o.valid_actions) v = std::bernoulli_distribution(0.5)(rng_);
      o.valid_actions[spot_] = 1;
    } else {
      o.vector = {offset_, 0.3f};
      o.valid_actions.clear();
    }
  }
  rl::StepResult step(const rl::Action& a, rl::Observation& next) override {
    rl::StepResult r;
    if (discrete_) {
      r.reward = a.discrete == spot_ ? 1.0f : 0.0f;
    } else {
      const float target = 0.5f * (2.0f * spot_ / (positions_ - 1) - 1.0f) + 0.5f * offset_;
      r.reward = -std::abs(a.continuous[0] - target);
    }
    r.terminated = true;
    reset(next);
    return r;
  }

 private:
  bool discrete_;
  int positions_;
  int spot_ = 0;
  float offset_ = 0;
  std::mt19937_64 rng_{0};
};

// An env loop whose state survives between calls (for checkpoint tests).
struct Rollout {
  rl::Env& env;
  rl::Observation obs, next;
  rl::Action action;
  Rollout(rl::Env& e) : env(e) { env.reset(obs); }
  // Runs n steps; appends every action's first component and every reward.
  void run(rl::Learner& learner, int n, std::vector<double>& trace) {
    for (int t = 0; t < n; ++t) {
      learner.act(obs, true, action);
      trace.push_back(action.continuous.empty() ? action.discrete : action.continuous[0]);
      const rl::StepResult r = env.step(action, next);
      learner.store(obs, action, r.reward, next, r.terminated, r.truncated);
      trace.push_back(r.reward);
      if (r.terminated || r.truncated) env.reset(obs);
      else std::swap(obs, next);
      for (int u = learner.updates_due(); u > 0; --u) learner.update();
    }
  }
};

YAML::Node small_td3() {
  return YAML::Load(
      "{actor_learning_rate: 1.0e-3, critic_learning_rate: 1.0e-3, batch_size: 64, buffer_size: 5000,"
      " learning_starts: 200, random_action_steps: 200, hidden_sizes: [64, 64]}");
}
YAML::Node small_sac() {
  return YAML::Load(
      "{batch_size: 64, buffer_size: 5000, learning_starts: 200, random_action_steps: 200,"
      " hidden_sizes: [64, 64]}");
}
YAML::Node small_dqn() {
  return YAML::Load(
      "{learning_rate: 1.0e-3, batch_size: 32, buffer_size: 5000, learning_starts: 100,"
      " train_frequency: 4, target_update_interval: 50, epsilon_decay: 500, hidden_sizes: [32]}");
}

}  // namespace

// ---- learning ------------------------------------------------------------------

TEST(Learning, DqnSolvesCartPole) {
  rl::CartPoleEnv env, eval_env;
  env.seed(1);
  eval_env.seed(2);
  YAML::Node config = rl::load_yaml_file(rl::classic_config_path("cartpole", "dqn"));
  config["hidden_sizes"] = std::vector<int>{64, 64};
  config["gradient_steps"] = 64;  // half the updates of the preset: faster, still learns
  auto learner = rl::make_learner("dqn", env.observation_spec(), env.action_spec(), config, "test", 1);
  const double untrained = mean(rl::evaluate(eval_env, *learner, 5));
  rl::train(env, *learner, 25000);
  const double trained = mean(rl::evaluate(eval_env, *learner, 5));
  // Random/untrained policies last ~10-50 steps.
  EXPECT_LT(untrained, 150);
  EXPECT_GT(trained, 150) << "untrained " << untrained;
}

TEST(Learning, Td3SwingsUpPendulum) {
  rl::PendulumEnv env, eval_env;
  env.seed(1);
  eval_env.seed(2);
  auto learner = rl::make_learner("td3", env.observation_spec(), env.action_spec(), small_td3(), "test", 1);
  const double untrained = mean(rl::evaluate(eval_env, *learner, 5));
  rl::train(env, *learner, 6000);
  const double trained = mean(rl::evaluate(eval_env, *learner, 5));
  // Untrained/broken controllers score about -1200 .. -1600; solved is about -150.
  EXPECT_LT(untrained, -700);
  EXPECT_GT(trained, -700) << "untrained " << untrained;
}

TEST(Learning, SacSwingsUpPendulum) {
  rl::PendulumEnv env, eval_env;
  env.seed(1);
  eval_env.seed(2);
  auto learner = rl::make_learner("sac", env.observation_spec(), env.action_spec(), small_sac(), "test", 1);
  const double untrained = mean(rl::evaluate(eval_env, *learner, 5));
  rl::train(env, *learner, 6000);
  const double trained = mean(rl::evaluate(eval_env, *learner, 5));
  EXPECT_LT(untrained, -700);
  EXPECT_GT(trained, -700) << "untrained " << untrained;
}

TEST(Learning, DqnReadsImagesWithThePaperNetworkAndMask) {
  SpotEnv env(true, 4), eval_env(true, 4);
  env.seed(1);
  eval_env.seed(2);
  YAML::Node config = small_dqn();
  config["hidden_sizes"] = std::vector<int>{};  // image only: conv-pool-conv-pool-FC256-FC4
  config["train_frequency"] = 1;
  auto learner = rl::make_learner("dqn", env.observation_spec(), env.action_spec(), config, "test", 1);
  const double untrained = mean(rl::evaluate(eval_env, *learner, 100));
  rl::train(env, *learner, 800);
  const double trained = mean(rl::evaluate(eval_env, *learner, 100));
  // Chance among the valid actions is about 0.45.
  EXPECT_GT(trained, 0.9) << "untrained " << untrained;
  EXPECT_LT(untrained, 0.9);
}

TEST(Learning, Td3ReadsImagePlusVectorThroughTheSharedEncoder) {
  SpotEnv env(false, 4), eval_env(false, 4);
  env.seed(1);
  eval_env.seed(2);
  YAML::Node config = small_td3();
  config["share_encoder"] = true;
  config["image_features"] = 8;
  auto learner = rl::make_learner("td3", env.observation_spec(), env.action_spec(), config, "test", 1);
  const double untrained = mean(rl::evaluate(eval_env, *learner, 100));
  rl::train(env, *learner, 1500);
  const double trained = mean(rl::evaluate(eval_env, *learner, 100));
  // A constant action scores about -0.45; the exact answer scores 0.
  EXPECT_GT(trained, -0.15) << "untrained " << untrained;
  EXPECT_LT(untrained, -0.15);
}

// ---- determinism ----------------------------------------------------------------

TEST(Determinism, SameSeedSameReturnsDifferentSeedDifferent) {
  auto run = [](const std::string& algo, std::uint64_t seed) {
    std::unique_ptr<rl::Env> env = rl::make_classic_env(algo == "dqn" ? "cartpole" : "pendulum");
    env->seed(seed);
    const YAML::Node config = algo == "td3" ? small_td3() : algo == "sac" ? small_sac() : small_dqn();
    auto learner = rl::make_learner(algo, env->observation_spec(), env->action_spec(), config, "t", seed);
    std::vector<double> returns = rl::train(*env, *learner, 1000).episode_returns;
    for (double r : rl::evaluate(*env, *learner, 2)) returns.push_back(r);
    return returns;
  };
  for (const std::string algo : {"td3", "sac", "dqn"}) {
    const std::vector<double> a = run(algo, 11), b = run(algo, 11), c = run(algo, 12);
    EXPECT_EQ(a, b) << algo;
    EXPECT_NE(a, c) << algo;
  }
}

// ---- checkpoints ----------------------------------------------------------------

namespace {

// Trains `first` steps, saves, trains `second` more; a fresh learner (other
// seed) loads the checkpoint and trains the same `second` steps from a copy of
// the env: actions, rewards and final parameters must be identical.
template <typename EnvT>
void expect_exact_resume(const std::string& algo, EnvT env, const YAML::Node& config, int first,
                         int second) {
  env.seed(5);
  auto a = rl::make_learner(algo, env.observation_spec(), env.action_spec(), config, "t", 5);
  Rollout ra(env);
  std::vector<double> trace_a, trace_b;
  ra.run(*a, first, trace_a);
  const std::string path = temp_path(algo + "_checkpoint.pt");
  a->save(path);

  EnvT env_b = static_cast<EnvT&>(ra.env);  // the env's state and RNG at the save
  auto b = rl::make_learner(algo, env.observation_spec(), env.action_spec(), config, "t", 999);
  b->load(path);
  Rollout rb(env_b);
  rb.obs = ra.obs;
  trace_a.clear();
  ra.run(*a, second, trace_a);
  rb.run(*b, second, trace_b);
  EXPECT_EQ(trace_a, trace_b) << algo;
  EXPECT_EQ(a->counters().updates, b->counters().updates);
  EXPECT_GT(a->counters().updates, 0);
  // One more update from identical state gives identical losses.
  a->update();
  b->update();
  EXPECT_EQ(a->last_loss(), b->last_loss()) << algo;
  std::filesystem::remove(path);
}

}  // namespace

TEST(Checkpoint, Td3ResumesExactlyWithImagesAndVector) {
  YAML::Node config = small_td3();
  config["batch_size"] = 16;
  config["learning_starts"] = 50;
  config["random_action_steps"] = 50;
  expect_exact_resume("td3", SpotEnv(false, 4), config, 120, 60);
  config["share_encoder"] = false;
  expect_exact_resume("td3", SpotEnv(false, 4), config, 120, 60);
}

TEST(Checkpoint, SacResumesExactlyOnPendulum) {
  YAML::Node config = small_sac();
  config["learning_starts"] = 100;
  config["random_action_steps"] = 100;
  expect_exact_resume("sac", rl::PendulumEnv(), config, 250, 150);  // saved mid-episode
}

TEST(Checkpoint, DqnResumesExactlyWithImagesAndMask) {
  YAML::Node config = small_dqn();
  config["hidden_sizes"] = std::vector<int>{};
  config["learning_starts"] = 40;
  config["target_update_interval"] = 7;
  expect_exact_resume("dqn", SpotEnv(true, 4), config, 101, 80);
}

TEST(Checkpoint, RejectsTheWrongAlgorithm) {
  rl::PendulumEnv env;
  auto td3 = rl::make_learner("td3", env.observation_spec(), env.action_spec(), small_td3(), "t", 1);
  auto sac = rl::make_learner("sac", env.observation_spec(), env.action_spec(), small_sac(), "t", 1);
  const std::string path = temp_path("wrong.pt");
  td3->save(path);
  EXPECT_THROW(sac->load(path), std::exception);
  std::filesystem::remove(path);
}
