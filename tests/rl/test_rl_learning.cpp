// Learning tests of DQN, TD3 and SAC; determinism, checkpoint and policy tests
// of every registered learner (rl/registry.hpp).
//
// Learning tests use short runs whose thresholds leave a margin above what
// the untrained (or broken) learner gets; each test also checks that the
// untrained learner fails the same threshold, so that the test can fail.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <unistd.h>

#include <filesystem>
#include <functional>
#include <map>
#include <numeric>
#include <random>

#include "rl/classic/cartpole.hpp"
#include "rl/classic/pendulum.hpp"
#include "rl/dqn.hpp"
#include "rl/learner.hpp"
#include "rl/registry.hpp"
#include "rl/sac.hpp"
#include "rl/td3.hpp"
#include "rl/train_classic.hpp"

namespace rl = comorph::rl;

namespace {

struct SingleThread {
  SingleThread() { rl::set_torch_threads(1, 1); }
} single_thread;

std::string temp_path(const std::string& name) {
  // The pid keeps concurrent test runs (other build trees) apart.
  return (std::filesystem::temp_directory_path() /
          ("comorph_rl_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

double mean(const std::vector<double>& v) {
  return std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

// A one-step task with an image and a vector: a bright 2x2 spot sits in one
// of `positions` horizontal positions of a 1 x 8 x 8 depth image (background
// 0.01, the paper's range). Discrete: pick the spot's position (reward 1,
// else 0) among the valid actions, which always include the right one.
// Continuous: output a = (spot position scaled to [-1, 1]) + 0.5 * vector[0];
// reward -|a - target|. Every step terminates the episode.
class SpotEnv final : public rl::Env {
 public:
  SpotEnv(bool discrete, int positions) : discrete_(discrete), positions_(positions) {}
  std::string name() const override { return "Spot"; }
  rl::ObservationSpec observation_spec() const override { return {1, 8, 8, discrete_ ? 0 : 2}; }
  rl::ActionSpec action_spec() const override {
    return discrete_ ? rl::ActionSpec{rl::ActionKind::kDiscrete, positions_}
                     : rl::ActionSpec{rl::ActionKind::kContinuous, 1};
  }
  void seed(std::uint64_t seed) override { rng_.seed(seed); }
  void reset(rl::Observation& o) override {
    spot_ = std::uniform_int_distribution<int>(0, positions_ - 1)(rng_);
    offset_ = std::uniform_real_distribution<float>(-1.0f, 1.0f)(rng_);
    o.image.assign(64, 0.01f);
    const int x0 = spot_ * (8 - 2) / (positions_ - 1);
    for (int y = 3; y < 5; ++y)
      for (int x = x0; x < x0 + 2; ++x) o.image[y * 8 + x] = 1.0f;
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

// A point on a line, x in [-2, 2], moved by the action: x' = x + 0.1 a;
// reward -x^2; 40 steps, then truncated (never terminated), so that the
// value must be bootstrapped through the truncation. Starting at
// x ~ U(-1, 1): doing nothing scores about -13, going to 0 at full speed
// about -1.
class PointEnv final : public rl::Env {
 public:
  std::string name() const override { return "Point"; }
  rl::ObservationSpec observation_spec() const override { return {0, 0, 0, 1}; }
  rl::ActionSpec action_spec() const override { return {rl::ActionKind::kContinuous, 1}; }
  void seed(std::uint64_t seed) override { rng_.seed(seed); }
  void reset(rl::Observation& o) override {
    x_ = std::uniform_real_distribution<double>(-1.0, 1.0)(rng_);
    steps_ = 0;
    o.vector = {static_cast<float>(x_)};
  }
  rl::StepResult step(const rl::Action& a, rl::Observation& next) override {
    x_ = std::clamp(x_ + 0.1 * a.continuous[0], -2.0, 2.0);
    rl::StepResult r;
    r.reward = static_cast<float>(-x_ * x_);
    r.truncated = ++steps_ >= 40;
    next.vector = {static_cast<float>(x_)};
    return r;
  }

 private:
  double x_ = 0;
  int steps_ = 0;
  std::mt19937_64 rng_{0};
};

// A corridor of 8 cells (one-hot observation); action 0 steps left, 1 right.
// Reaching cell 7 pays 1 and terminates; 30 steps truncate. From cell 0 the
// optimal return is 1 and Q*(cell 0, right) = gamma^6.
class CorridorEnv final : public rl::Env {
 public:
  std::string name() const override { return "Corridor"; }
  rl::ObservationSpec observation_spec() const override { return {0, 0, 0, 8}; }
  rl::ActionSpec action_spec() const override { return {rl::ActionKind::kDiscrete, 2}; }
  void seed(std::uint64_t) override {}
  void reset(rl::Observation& o) override {
    cell_ = 0;
    steps_ = 0;
    observe(o);
  }
  rl::StepResult step(const rl::Action& a, rl::Observation& next) override {
    cell_ = std::clamp(cell_ + (a.discrete == 1 ? 1 : -1), 0, 7);
    rl::StepResult r;
    r.terminated = cell_ == 7;
    r.reward = r.terminated ? 1.0f : 0.0f;
    r.truncated = !r.terminated && ++steps_ >= 30;
    observe(next);
    return r;
  }
  void observe(rl::Observation& o) const {
    o.vector.assign(8, 0.0f);
    o.vector[cell_] = 1.0f;
  }

 private:
  int cell_ = 0, steps_ = 0;
};

// An env loop whose state survives between calls (for checkpoint tests).
struct Rollout {
  rl::Env& env;
  rl::Observation obs, next;
  rl::Action action;
  Rollout(rl::Env& e, const rl::Observation* resume_from = nullptr) : env(e) {
    if (resume_from) obs = *resume_from;  // continue where a saved run stopped
    else env.reset(obs);
  }
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

TEST(Learning, DqnLearnsCorridorValues) {
  CorridorEnv env, eval_env;
  YAML::Node config = small_dqn();
  config["gamma"] = 0.9;
  config["epsilon_decay"] = 2000;
  auto learner = rl::make_learner("dqn", env.observation_spec(), env.action_spec(), config, "test", 1);
  EXPECT_LT(mean(rl::evaluate(eval_env, *learner, 1)), 1.0);  // untrained: walks into a wall
  rl::train(env, *learner, 4000);
  EXPECT_EQ(mean(rl::evaluate(eval_env, *learner, 1)), 1.0);
  // The values follow gamma^(steps to the goal - 1): bootstrapping, terminal handling.
  auto& dqn = static_cast<rl::Dqn&>(*learner);
  rl::Observation o;
  for (int cell : {0, 3, 6}) {
    o.vector.assign(8, 0.0f);
    o.vector[cell] = 1.0f;
    EXPECT_NEAR(dqn.q_values(o)[1], std::pow(0.9, 6 - cell), 0.08) << "cell " << cell;
  }
}

// One decision, two chains: a risky one returns 10 in 70 % of the cases and 0
// otherwise (mean 7, median 10), a sure one always 9. With returns far above
// the Huber loss's delta of 1, its gradient is the error's sign, so Huber
// regresses the median and prefers the risky chain; MSE learns the means and
// prefers the sure one. The configuration model's returns (hundreds, with
// stalls on the stairs among them) are in this regime (configs/standard.yaml).
namespace {
// A DQN (small_dqn + `extra`) trained on 3000 alternating tries of the two
// chains, whose returns are multiplied by `payout`.
std::unique_ptr<rl::Learner> dqn_on_risky_and_sure_chains(const rl::Observation& o, const YAML::Node& extra,
                                                          float payout = 1.0f) {
  YAML::Node config = small_dqn();
  config["train_frequency"] = 1;
  for (const auto& kv : extra) config[kv.first.Scalar()] = kv.second;
  auto learner = rl::make_learner("dqn", rl::ObservationSpec{0, 0, 0, 1}, {rl::ActionKind::kDiscrete, 2}, config,
                                  "test", 1);
  std::mt19937_64 rng(7);
  std::bernoulli_distribution risky_pays(0.7);
  rl::Action a;
  for (int i = 0; i < 3000; ++i) {
    a.discrete = i % 2;
    const float r = payout * (a.discrete == 0 ? (risky_pays(rng) ? 10.0f : 0.0f) : 9.0f);
    learner->store(o, a, r, o, /*terminated=*/true, false);
    for (int u = learner->updates_due(); u > 0; --u) learner->update();
  }
  return learner;
}

// Q near the means (7 and 9, in units of the payout) and the greedy choice the sure chain.
void expect_the_means_and_the_sure_chain(rl::Dqn& dqn, const rl::Observation& o) {
  const std::vector<float> q = dqn.q_values(o);
  EXPECT_NEAR(q[0], 7.0, 0.8);
  EXPECT_NEAR(q[1], 9.0, 0.5);
  rl::Action greedy;
  dqn.act(o, /*explore=*/false, greedy);
  EXPECT_EQ(greedy.discrete, 1);
}
}  // namespace

TEST(Learning, DqnMseLearnsMeanReturnsWhereHuberLearnsMedians) {
  rl::Observation o;
  o.vector = {1.0f};
  for (const char* loss : {"mse", "huber"}) {
    YAML::Node extra;
    extra["loss"] = loss;
    auto learner = dqn_on_risky_and_sure_chains(o, extra);
    auto& dqn = static_cast<rl::Dqn&>(*learner);
    const std::vector<float> q = dqn.q_values(o);
    if (std::string(loss) == "mse") {
      expect_the_means_and_the_sure_chain(dqn, o);
    } else {
      EXPECT_GT(q[0], 9.3) << "Huber: the risky chain's median, 10";
      EXPECT_GT(q[0], q[1]);
    }
  }
}

// The same bandit with an ensemble of three Q networks: every member learns
// the means (each regresses on the target, not only their mean), so the
// greedy choice is the sure chain.
TEST(Learning, DqnEnsembleMembersEachLearnTheMeanReturns) {
  rl::Observation o;
  o.vector = {1.0f};
  YAML::Node extra;
  extra["loss"] = "mse";
  extra["ensemble_size"] = 3;
  auto learner = dqn_on_risky_and_sure_chains(o, extra);
  auto& dqn = static_cast<rl::Dqn&>(*learner);
  torch::NoGradGuard no_grad;
  const torch::Tensor members =
      dqn.target_network()->forward_members(torch::Tensor(), torch::ones({1, 1}));  // [3, 1, 2]
  ASSERT_EQ(members.size(0), 3);
  for (int m = 0; m < 3; ++m) {  // the target copy of each member (synced every 50 updates)
    EXPECT_NEAR(members[m][0][0].item<float>(), 7.0, 1.0) << "member " << m;
    EXPECT_NEAR(members[m][0][1].item<float>(), 9.0, 0.7) << "member " << m;
  }
  expect_the_means_and_the_sure_chain(dqn, o);
}

// The same bandit paying 100 times as much (returns of hundreds, as R2's):
// in the same number of updates the network reaches nowhere near such values;
// with dqn.reward_scale 0.01 it learns the means in units of 100 and prefers
// the sure chain again.
TEST(Learning, DqnRewardScaleLetsItFitReturnsOfHundreds) {
  rl::Observation o;
  o.vector = {1.0f};
  YAML::Node extra;
  extra["loss"] = "mse";
  const std::vector<float> unscaled =
      static_cast<rl::Dqn&>(*dqn_on_risky_and_sure_chains(o, extra, 100.0f)).q_values(o);
  EXPECT_LT(unscaled[1], 700.0) << "the sure chain's mean is 900";
  extra["reward_scale"] = 0.01;
  auto learner = dqn_on_risky_and_sure_chains(o, extra, 100.0f);
  auto& dqn = static_cast<rl::Dqn&>(*learner);
  expect_the_means_and_the_sure_chain(dqn, o);
}

TEST(Learning, Td3DrivesPointToOrigin) {
  PointEnv env, eval_env;
  env.seed(1);
  eval_env.seed(2);
  auto learner = rl::make_learner("td3", env.observation_spec(), env.action_spec(), small_td3(), "test", 1);
  const double untrained = mean(rl::evaluate(eval_env, *learner, 20));
  rl::train(env, *learner, 2500);
  const double trained = mean(rl::evaluate(eval_env, *learner, 20));
  EXPECT_GT(trained, -3.0) << "untrained " << untrained;  // optimal about -1, idle about -13
  EXPECT_LT(untrained, -3.0);
}

TEST(Learning, SacDrivesPointToOrigin) {
  PointEnv env, eval_env;
  env.seed(1);
  eval_env.seed(2);
  auto learner = rl::make_learner("sac", env.observation_spec(), env.action_spec(), small_sac(), "test", 1);
  const double untrained = mean(rl::evaluate(eval_env, *learner, 20));
  rl::train(env, *learner, 2500);
  const double trained = mean(rl::evaluate(eval_env, *learner, 20));
  EXPECT_GT(trained, -3.0) << "untrained " << untrained;
  EXPECT_LT(untrained, -3.0);
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
  config["batch_size"] = 32;
  config["share_encoder"] = true;
  config["image_features"] = 8;
  auto learner = rl::make_learner("td3", env.observation_spec(), env.action_spec(), config, "test", 1);
  const double untrained = mean(rl::evaluate(eval_env, *learner, 100));
  rl::train(env, *learner, 1000);
  const double trained = mean(rl::evaluate(eval_env, *learner, 100));
  // A constant action scores about -0.45; the exact answer scores 0.
  EXPECT_GT(trained, -0.15) << "untrained " << untrained;
  EXPECT_LT(untrained, -0.15);
}

// ---- every registered learner: determinism, checkpoints, policy ----------------------

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
  Rollout rb(env_b, &ra.obs);
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

// What the tests below need of each registered learner: the classic env and
// small config of the determinism runs, and the checkpoint cases.
struct LearnerCase {
  std::string classic_env;
  YAML::Node config;
  std::function<void(const std::string& algo)> resume;
};

const std::map<std::string, LearnerCase>& learner_cases() {
  static const std::map<std::string, LearnerCase> cases{
      {"td3", {"pendulum", small_td3(),
               [](const std::string& algo) {  // images and vector, shared and separate encoders
                 YAML::Node config = small_td3();
                 config["batch_size"] = 16;
                 config["learning_starts"] = 50;
                 config["random_action_steps"] = 50;
                 expect_exact_resume(algo, SpotEnv(false, 4), config, 120, 60);
                 config["share_encoder"] = false;
                 expect_exact_resume(algo, SpotEnv(false, 4), config, 120, 60);
               }}},
      {"sac", {"pendulum", small_sac(),
               [](const std::string& algo) {
                 YAML::Node config = small_sac();
                 config["learning_starts"] = 100;
                 config["random_action_steps"] = 100;
                 expect_exact_resume(algo, rl::PendulumEnv(), config, 250, 150);  // saved mid-episode
               }}},
      {"dqn", {"cartpole", small_dqn(),
               [](const std::string& algo) {  // images and a mask
                 YAML::Node config = small_dqn();
                 config["hidden_sizes"] = std::vector<int>{};
                 config["learning_starts"] = 40;
                 config["target_update_interval"] = 7;
                 expect_exact_resume(algo, SpotEnv(true, 4), config, 101, 80);
               }}}};
  return cases;
}

class EveryLearner : public ::testing::TestWithParam<std::string> {
 protected:
  const LearnerCase& test_case() const {
    const auto it = learner_cases().find(GetParam());
    if (it == learner_cases().end()) throw std::logic_error("no test case for the registered learner " + GetParam());
    return it->second;
  }
};

TEST_P(EveryLearner, SameSeedSameReturnsDifferentSeedDifferent) {
  const std::string algo = GetParam();
  const LearnerCase& c = test_case();
  auto run = [&](std::uint64_t seed) {
    std::unique_ptr<rl::Env> env = rl::make_classic_env(c.classic_env);
    env->seed(seed);
    auto learner = rl::make_learner(algo, env->observation_spec(), env->action_spec(), c.config, "t", seed);
    std::vector<double> returns = rl::train(*env, *learner, 1000).episode_returns;
    for (double r : rl::evaluate(*env, *learner, 2)) returns.push_back(r);
    return returns;
  };
  const std::vector<double> a = run(11), b = run(11), c2 = run(12);
  EXPECT_EQ(a, b) << algo;
  EXPECT_NE(a, c2) << algo;
}

TEST_P(EveryLearner, ResumesExactlyFromACheckpoint) { test_case().resume(GetParam()); }

// The acting side alone: a policy of the learner's seed, synced from it, acts
// as the learner does (greedy and exploring, same RNG stream and counters),
// and keeps doing so through its own save and load.
TEST_P(EveryLearner, APolicySyncedFromItsLearnerActsAsTheLearner) {
  const std::string algo = GetParam();
  const LearnerCase& c = test_case();
  std::unique_ptr<rl::Env> env = rl::make_classic_env(c.classic_env);
  rl::LearnerArgs args;
  args.observation = env->observation_spec();
  args.action = env->action_spec();
  args.seed = 3;
  args.config = rl::learner_entry(algo).read_config(c.config, "t");
  auto learner = rl::make_learner(algo, args);
  auto policy = rl::make_policy(algo, args);
  policy->sync_from(*learner);
  rl::Observation o;
  env->seed(3);
  env->reset(o);
  rl::Action x, y;
  for (int i = 0; i < 5; ++i)
    for (bool explore : {false, true}) {
      learner->act(o, explore, x);
      policy->act(o, explore, y);
      EXPECT_EQ(x.discrete, y.discrete) << algo;
      EXPECT_EQ(x.continuous, y.continuous) << algo;
    }
  const std::string path = temp_path(algo + "_policy.pt");
  policy->save(path);
  auto loaded = rl::make_policy(algo, args);
  loaded->load(path);
  EXPECT_EQ(loaded->counters().transitions, policy->counters().transitions);
  for (bool explore : {false, true}) {
    policy->act(o, explore, x);
    loaded->act(o, explore, y);
    EXPECT_EQ(x.discrete, y.discrete) << algo;
    EXPECT_EQ(x.continuous, y.continuous) << algo;
  }
  std::filesystem::remove(path);
}

INSTANTIATE_TEST_SUITE_P(Registry, EveryLearner, ::testing::ValuesIn(rl::learner_names()),
                         [](const ::testing::TestParamInfo<std::string>& p) { return p.param; });

}  // namespace

TEST(Checkpoint, RejectsTheWrongAlgorithm) {
  rl::PendulumEnv env;
  auto td3 = rl::make_learner("td3", env.observation_spec(), env.action_spec(), small_td3(), "t", 1);
  auto sac = rl::make_learner("sac", env.observation_spec(), env.action_spec(), small_sac(), "t", 1);
  const std::string path = temp_path("wrong.pt");
  td3->save(path);
  EXPECT_THROW(sac->load(path), std::exception);
  std::filesystem::remove(path);
}
