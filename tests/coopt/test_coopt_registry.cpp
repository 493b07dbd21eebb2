// A learner registered from outside the libraries plugs into the trainer by
// name: a PPO-shaped stub (on-policy: it gathers a rollout, takes one gradient
// step on it when it is full, then starts a new one) trains ci-preset episodes
// through rl::register_learner, with nothing in src/coopt/ knowing it.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <algorithm>
#include <any>
#include <atomic>
#include <filesystem>
#include <random>

#include "coopt/config.hpp"
#include "coopt/trainer.hpp"
#include "rl/registry.hpp"
#include "rl/replay_buffer.hpp"
#include "support/test_support.hpp"

namespace comorph {
namespace {
namespace fs = std::filesystem;

constexpr int kRollout = 32;  // transitions per rollout
std::atomic<int> stub_updates{0};

// A Gaussian policy whose mean is tanh(W v + b) of the observation's vector.
torch::nn::Linear stub_net(const rl::LearnerArgs& a) {
  torch::manual_seed(a.seed);
  return torch::nn::Linear(a.observation.vector_size, a.action.size);
}

void stub_act(torch::nn::Linear& net, std::mt19937_64& rng, const rl::Observation& o, bool explore,
              rl::Action& action) {
  torch::Tensor mean;
  {
    torch::InferenceMode guard;
    mean = torch::tanh(net->forward(torch::from_blob(const_cast<float*>(o.vector.data()),
                                                     {1, static_cast<long>(o.vector.size())})));
  }
  action.continuous.resize(static_cast<std::size_t>(mean.size(1)));
  std::normal_distribution<float> noise(0.0f, 0.3f);
  for (std::size_t i = 0; i < action.continuous.size(); ++i)
    action.continuous[i] =
        std::clamp(mean[0][static_cast<long>(i)].item<float>() + (explore ? noise(rng) : 0.0f), -1.0f, 1.0f);
}

class PpoStub final : public rl::Learner {
 public:
  explicit PpoStub(const rl::LearnerArgs& a)
      : net_(stub_net(a)), optimizer_(net_->parameters(), torch::optim::AdamOptions(1e-3)),
        rollout_(a.observation, a.action, kRollout), rng_(a.seed) {}
  void act(const rl::Observation& o, bool explore, rl::Action& action) override {
    stub_act(net_, rng_, o, explore, action);
  }
  void store(const rl::Observation& o, const rl::Action& a, float reward, const rl::Observation& next,
             bool terminated, bool truncated, int) override {
    rollout_.add(o, a, reward, next, terminated, 0.99f);
    ++counters_.transitions;
    if (terminated || truncated) ++counters_.episodes;
  }
  int updates_due() const override { return counters_.transitions % kRollout == 0 ? 1 : 0; }
  void update() override {
    // The rollout, whole: reward-weighted regression of the mean towards the actions taken.
    const rl::ReplayBatch b = rollout_.gather(torch::arange(kRollout), torch::kCPU);
    const torch::Tensor advantage = b.reward - b.reward.mean();
    const torch::Tensor mean = torch::tanh(net_->forward(b.vector));
    const torch::Tensor loss = (advantage.unsqueeze(1) * (mean - b.action).pow(2)).mean();
    optimizer_.zero_grad();
    loss.backward();
    optimizer_.step();
    last_loss_ = loss.item<double>();
    ++counters_.updates;
    ++stub_updates;
  }
  void save(const std::string& path) const override {
    torch::serialize::OutputArchive a, net;
    rl::write_common(a, counters_, rng_, "ppo_stub");
    net_->save(net);
    a.write("networks", net);
    save_archive(a, path);
  }
  void save_without_replay(const std::string& path) const override { save(path); }
  void load(const std::string& path) override {
    torch::serialize::InputArchive a, net;
    a.load_from(path);
    rl::read_common(a, counters_, rng_, "ppo_stub");
    a.read("networks", net);
    net_->load(net);
  }
  void save_policy(const std::string& path) const override {
    rl::save_policy_file(path, *net_, "networks", counters_, rng_, "ppo_stub");
  }
  rl::ReplayBuffer& replay() override { return rollout_; }
  const rl::LearnerCounters& counters() const override { return counters_; }
  const torch::nn::Module& acting_networks() const override { return *net_; }
  double last_loss() const override { return last_loss_; }

 private:
  torch::nn::Linear net_;
  torch::optim::Adam optimizer_;
  rl::ReplayBuffer rollout_;
  std::mt19937_64 rng_;
  rl::LearnerCounters counters_;
  double last_loss_ = 0;
};

class PpoStubPolicy final : public rl::Policy {
 public:
  explicit PpoStubPolicy(const rl::LearnerArgs& a) : Policy("ppo_stub", "networks", "cpu", a.seed), net_(stub_net(a)) {}
  void act(const rl::Observation& o, bool explore, rl::Action& action) override {
    stub_act(net_, rng_, o, explore, action);
  }

 protected:
  torch::nn::Module& acting_module() const override { return *net_.ptr(); }

 private:
  torch::nn::Linear net_;
};

TEST(Registry, AnOnPolicyLearnerRegisteredOutsideTrainsThroughTheTrainer) {
  rl::LearnerEntry e;
  e.actions = rl::ActionKind::kContinuous;
  e.on_policy = true;
  // One setting, so that its section shows in `config keys` and in the run's config.yaml.
  e.default_config = [] { return std::any(0.5); };
  e.add_fields = [](YamlFields& f, std::any& config) {
    f.add("clip", &std::any_cast<double&>(config), 0.0, 1.0, "the stub's clip ratio");
  };
  e.read_config = [e](const YAML::Node& node, const std::string& source) {
    std::any config = e.default_config();
    YamlFields f(source);
    e.add_fields(f, config);
    f.apply(node);
    return config;
  };
  e.make_learner = [](const rl::LearnerArgs& a) { return std::make_unique<PpoStub>(a); };
  e.make_policy = [](const rl::LearnerArgs& a) { return std::make_unique<PpoStubPolicy>(a); };
  rl::register_learner("ppo_stub", e);

  const std::string dir = test_support::fresh_temp_dir("coopt_ppo_stub");
  const coopt::CooptConfig c = coopt::load_coopt_config(std::string(COMORPH_SOURCE_DIR) + "/configs/ci.yaml",
                                                        {"trainer.motion_algo=ppo_stub", "ppo_stub.clip=0.2"});
  // The registry gives the learner its section: read, resolved into the run's config, listed.
  EXPECT_EQ(std::any_cast<double>(c.other_learners.at("ppo_stub")), 0.2);
  EXPECT_NE(c.text.find("ppo_stub:\n  clip: 0.2"), std::string::npos) << c.text;
  bool listed = false;
  for (const auto& section : coopt::settings_sections(c)) listed = listed || section.name == "ppo_stub";
  EXPECT_TRUE(listed);
  EXPECT_NE(test_support::error_of([] {
              coopt::load_coopt_config(std::string(COMORPH_SOURCE_DIR) + "/configs/ci.yaml", {"ppo_stub.clip=2"});
            }).find("ppo_stub: field 'clip': value 2 out of range [0, 1]"),
            std::string::npos);
  int episodes = 0;
  coopt::TrainerCallbacks cb;
  cb.on_episode = [&episodes](const coopt::EpisodeLog& l) {
    ++episodes;
    EXPECT_GT(l.steps, 0);
  };
  {
    coopt::Trainer t(c, dir, cb);
    ASSERT_TRUE(t.run());
    EXPECT_EQ(t.episodes_done(), c.trainer.total_episodes());
    EXPECT_EQ(t.env_steps() / kRollout, stub_updates.load());  // one update per full rollout
  }
  EXPECT_EQ(episodes, c.trainer.total_episodes());
  EXPECT_GT(stub_updates.load(), 0);
  // Its checkpoint (no replay segments: its rollout is its own) resumes.
  coopt::Trainer again(c, dir);
  again.resume();
  EXPECT_EQ(again.episodes_done(), c.trainer.total_episodes());
  EXPECT_FALSE(fs::exists(fs::path(dir) / "checkpoint" / "motion-replay.yaml"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace comorph
