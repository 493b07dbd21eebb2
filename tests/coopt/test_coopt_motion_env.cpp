// MotionEnv: the robot's motion level as an rl::Env. The trainer's motion
// observation, R1 and the env's episode ends come through the adapter: the
// scripted pilot succeeds through it, the step cap truncates, and rl's generic
// training loop trains a TD3 on it, the same way twice for one seed.
#include <gtest/gtest.h>

#include <array>
#include <string>
#include <vector>

#include "coopt/config.hpp"
#include "coopt/motion_env.hpp"
#include "rl/learner_params.hpp"
#include "rl/registry.hpp"
#include "rl/train_classic.hpp"
#include "task/scripted_pilot.hpp"

namespace comorph {
namespace {

coopt::CooptConfig ci_config(std::vector<std::string> sets = {}) {
  return coopt::load_coopt_config(std::string(COMORPH_SOURCE_DIR) + "/configs/ci.yaml", sets);
}

TEST(MotionEnv, DeclaresTheTrainersMotionSpecAndRefusesBadChains) {
  const coopt::CooptConfig c = ci_config();
  coopt::MotionEnv env(c, 4);
  EXPECT_EQ(env.name(), "robot-chain4");
  const rl::ObservationSpec s = env.observation_spec();
  EXPECT_EQ(s.image_size(), 8 * 8);  // ci.yaml: the motion model keeps an 8x8 depth image
  EXPECT_EQ(s.vector_size, task::obs::kStateSize);
  EXPECT_EQ(env.action_spec().size, control::kActionSize);
  // With the clearance input and no image (the standard preset's choice).
  coopt::MotionEnv scan(ci_config({"trainer.motion_clearance=true", "trainer.motion_image=false"}), 4);
  EXPECT_EQ(scan.observation_spec().image_size(), 0);
  EXPECT_EQ(scan.observation_spec().vector_size, task::obs::kStateSize + scan.env().clearance_width());
  EXPECT_THROW(coopt::MotionEnv(c, 1), std::invalid_argument);
  EXPECT_THROW(coopt::MotionEnv(c, kMaxModules + 1), std::invalid_argument);
}

// trainer.motion_heads_per_chain: the vector ends with a one-hot of the
// chain's length (2..10 modules), declared as the actor's head selector, and
// a TD3 motion model gets one head per length; SAC is refused by name.
TEST(MotionEnv, HeadsPerChainAppendTheChainLengthAsTheHeadSelector) {
  const std::vector<std::string> sets{"trainer.motion_clearance=true", "trainer.motion_image=false",
                                      "trainer.motion_heads_per_chain=true"};
  for (int modules : {2, 6, kMaxModules}) {
    coopt::MotionEnv env(ci_config(sets), modules);
    const rl::ObservationSpec s = env.observation_spec();
    const int lengths = kMaxModules - kMinModules + 1;
    EXPECT_EQ(s.head_selector, lengths);
    EXPECT_EQ(s.vector_size, task::obs::kStateSize + env.env().clearance_width() + lengths);
    rl::Observation o;
    rl::allocate(s, o);
    env.seed(5);
    env.reset(o);
    EXPECT_EQ(s.head_of(o.vector.data()), modules - kMinModules);
    float sum = 0;
    for (int k = 0; k < lengths; ++k) sum += o.vector[s.vector_size - lengths + k];
    EXPECT_EQ(sum, 1.0f);
  }
  std::vector<std::string> sac = sets;
  sac.push_back("trainer.motion_algo=sac");
  try {
    ci_config(sac);
    ADD_FAILURE() << "SAC with heads per chain was accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("trainer.motion_heads_per_chain"), std::string::npos) << e.what();
  }
}

TEST(MotionEnv, ScriptedPilotClimbsAndReachesTheTargetThroughIt) {
  coopt::MotionEnv env(ci_config({"env.task.max_steps=3500", "trainer.stair_height=0.04"}), 4);
  rl::Observation o;
  rl::allocate(env.observation_spec(), o);
  env.seed(11);
  env.reset(o);
  task::ScriptedPilot pilot(task::searched_stair_gaits());
  pilot.plan(env.env());
  rl::Action a;
  a.continuous.resize(control::kActionSize);
  double returns = 0;
  rl::StepResult r;
  int steps = 0;
  while (!r.terminated && !r.truncated) {
    control::MotionMode mode;
    pilot.act(env.env(), a.continuous.data(), mode);
    r = env.step(a, o);
    returns += r.reward;
    ++steps;
    // The motion observation carries the env's state (the battery share is not rescaled).
    ASSERT_FLOAT_EQ(o.vector[task::obs::kBattery], env.env().state()[task::obs::kBattery]);
  }
  EXPECT_TRUE(r.terminated);
  EXPECT_EQ(env.env().last().reason, task::Termination::success);
  EXPECT_TRUE(env.env().stairs_climbed());
  EXPECT_EQ(steps, env.env().step_count());
  EXPECT_GT(returns, 0);
}

TEST(MotionEnv, TheStepCapTruncates) {
  coopt::MotionEnv env(ci_config(), 2);  // ci.yaml: 120 control steps at most
  rl::Observation o;
  rl::allocate(env.observation_spec(), o);
  env.seed(3);
  env.reset(o);
  rl::Action still;
  still.continuous.assign(control::kActionSize, 0.0f);
  rl::StepResult r;
  int steps = 0;
  while (!r.terminated && !r.truncated) {
    r = env.step(still, o);
    ++steps;
  }
  EXPECT_TRUE(r.truncated);
  EXPECT_FALSE(r.terminated);
  EXPECT_EQ(steps, 120);
}

TEST(MotionEnv, RlsGenericLoopTrainsTd3OnItDeterministically) {
  const coopt::CooptConfig c = ci_config();
  auto run = [&] {
    coopt::MotionEnv env(c, 4);
    env.seed(21);
    rl::LearnerArgs args;
    args.observation = env.observation_spec();
    args.action = env.action_spec();
    args.seed = 5;
    args.config = c.td3;
    auto learner = rl::make_learner("td3", args);
    const rl::TrainStats stats = rl::train(env, *learner, 400);
    EXPECT_EQ(stats.steps, 400);
    EXPECT_GT(learner->counters().updates, 0);  // learning_starts 64, an update every 4 steps
    return stats.episode_returns;
  };
  const std::vector<double> first = run();
  EXPECT_GE(first.size(), 3u);  // episodes of at most 120 steps
  EXPECT_EQ(first, run());
}

}  // namespace
}  // namespace comorph
