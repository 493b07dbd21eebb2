// The acting protocol's values as bytes (coopt/acting.hpp): what an actor rank
// and the host send each other reads back field for field, into buffers
// allocated once.
#include <gtest/gtest.h>

#include <string>

#include "coopt/acting.hpp"
#include "coopt/config.hpp"

namespace comorph::coopt {
namespace {

const std::string kCi = std::string(COMORPH_SOURCE_DIR) + "/configs/ci.yaml";

// Every float of a transition distinct, from `x` on.
void fill(Transition& t, float x) {
  for (auto* v : {&t.obs.image, &t.obs.vector, &t.next.image, &t.next.vector, &t.action.continuous, &t.action.target})
    for (float& f : *v) f = x++;
  t.reward = x;
  t.terminated = true;
  t.steps = 3;
}

void expect_same(const Transition& a, const Transition& b) {
  EXPECT_EQ(a.obs.image, b.obs.image);
  EXPECT_EQ(a.obs.vector, b.obs.vector);
  EXPECT_EQ(a.obs.valid_actions, b.obs.valid_actions);
  EXPECT_EQ(a.next.image, b.next.image);
  EXPECT_EQ(a.next.vector, b.next.vector);
  EXPECT_EQ(a.next.valid_actions, b.next.valid_actions);
  EXPECT_EQ(a.action.discrete, b.action.discrete);
  EXPECT_EQ(a.action.continuous, b.action.continuous);
  EXPECT_EQ(a.action.target, b.action.target);
  EXPECT_EQ(a.reward, b.reward);
  EXPECT_EQ(a.terminated, b.terminated);
  EXPECT_EQ(a.truncated, b.truncated);
  EXPECT_EQ(a.steps, b.steps);
}

TEST(ActingBytes, ARolloutReadsBackFieldForField) {
  const CooptConfig c = load_coopt_config(kCi);
  Rollout r;
  allocate_transitions(c, r.transitions, 4);
  r.stored = 2;
  r.steps = 7;
  fill(r.transitions[0], 1);
  fill(r.transitions[1], 1000);
  StoredDecision& d = r.decisions.emplace_back();
  d.transition.obs.image = {0.5f, 0.25f};
  d.transition.obs.valid_actions = {1, 0, 1};
  d.transition.action.discrete = 4;
  d.transition.reward = -2.5f;
  d.k = 41;
  DecisionLog& dl = r.decision_logs.emplace_back();
  dl.episode = 9;
  dl.r2 = 1.5;
  dl.next_max_modules = 6;
  r.ended = true;
  r.log.episode = 9;
  r.log.seed = 123456789012345ULL;
  r.log.scenario = "obstacles7";
  r.log.termination = "step_cap";
  r.log.configurations = {7, 4};
  r.log.return_R1 = 3.25;
  r.log.return_R2 = -1.75;
  r.log.F = 0.625;
  r.log.steps = 120;
  r.log.switches = 2;
  r.log.stairs_energy_J = 42.5;
  r.log.first_segment_R2 = 7.5;
  r.log.first_segment_R1 = 8.5;
  r.log.first_segment_steps = 60;
  r.log.warmup = true;
  r.log.action_saturation = 0.125;
  r.rng.discard(3);
  r.motion_rng.discard(5);
  r.config_rng.discard(7);
  r.motion_counters = {11, 2, 5};
  r.actor_time[kEnvStep] = Clock::duration(12345);

  std::vector<char> bytes;
  rollout_to_bytes(r, bytes);
  Rollout back;
  allocate_transitions(c, back.transitions, 4);
  const float* storage = back.transitions[1].obs.vector.data();
  rollout_from_bytes(bytes, back);
  EXPECT_EQ(back.transitions[1].obs.vector.data(), storage) << "read into the preallocated transition";
  ASSERT_EQ(back.stored, 2);
  EXPECT_EQ(back.steps, 7);
  for (int i = 0; i < 2; ++i) expect_same(back.transitions[i], r.transitions[i]);
  ASSERT_EQ(back.decisions.size(), 1u);
  expect_same(back.decisions[0].transition, d.transition);
  EXPECT_EQ(back.decisions[0].k, 41);
  ASSERT_EQ(back.decision_logs.size(), 1u);
  EXPECT_EQ(back.decision_logs[0].episode, 9);
  EXPECT_EQ(back.decision_logs[0].r2, 1.5);
  EXPECT_EQ(back.decision_logs[0].next_max_modules, 6);
  ASSERT_TRUE(back.ended);
  const EpisodeLog& l = back.log;
  EXPECT_EQ(l.episode, 9);
  EXPECT_EQ(l.seed, 123456789012345ULL);
  EXPECT_EQ(l.scenario, "obstacles7");
  EXPECT_EQ(l.termination, "step_cap");
  EXPECT_EQ(l.configurations, (std::vector<int>{7, 4}));
  EXPECT_EQ(l.return_R1, 3.25);
  EXPECT_EQ(l.return_R2, -1.75);
  EXPECT_EQ(l.F, 0.625);
  EXPECT_EQ(l.steps, 120);
  EXPECT_EQ(l.switches, 2);
  EXPECT_EQ(l.stairs_energy_J, 42.5);
  EXPECT_EQ(l.first_segment_R2, 7.5);
  EXPECT_EQ(l.first_segment_R1, 8.5);
  EXPECT_EQ(l.first_segment_steps, 60);
  EXPECT_TRUE(l.warmup);
  EXPECT_EQ(l.action_saturation, 0.125);
  EXPECT_EQ(back.rng, r.rng);
  EXPECT_EQ(back.motion_rng, r.motion_rng);
  EXPECT_EQ(back.config_rng, r.config_rng);
  EXPECT_EQ(back.motion_counters.transitions, 11);
  EXPECT_EQ(back.motion_counters.updates, 5);
  EXPECT_EQ(back.actor_time[kEnvStep], Clock::duration(12345));

  bytes.pop_back();
  EXPECT_THROW(rollout_from_bytes(bytes, back), std::runtime_error) << "a cut message is refused";
}

TEST(ActingBytes, AReleaseSendsWeightsOnlyForANewVersion) {
  ActingWeights w;
  w.motion_version = 3;
  w.motion = {1, 2, 3};
  w.config_version = 2;
  w.config_refit = true;
  w.config = {4, 5};
  w.config_counters = {6, 7, 8};
  Orders o;
  o.episode = 12;
  o.start = true;
  o.rng.discard(1);
  o.motion_rng.discard(2);
  o.set_motion_counters = true;
  o.motion_counters = {100, 12, 0};
  o.set_config_rng = true;
  o.config_rng.discard(3);
  o.stair_height_m = 0.08;

  std::vector<char> bytes;
  release_to_bytes(w, o, true, true, bytes);
  ActingWeights wb;
  Orders ob;
  release_from_bytes(bytes, wb, ob);
  EXPECT_EQ(wb.motion_version, 3u);
  EXPECT_EQ(wb.motion, w.motion);
  EXPECT_EQ(wb.config_version, 2u);
  EXPECT_TRUE(wb.config_refit);
  EXPECT_EQ(wb.config, w.config);
  EXPECT_EQ(wb.config_counters.episodes, 7);
  EXPECT_EQ(ob.episode, 12);
  EXPECT_TRUE(ob.start);
  EXPECT_EQ(ob.rng, o.rng);
  EXPECT_EQ(ob.motion_rng, o.motion_rng);
  EXPECT_TRUE(ob.set_motion_counters);
  EXPECT_EQ(ob.motion_counters.transitions, 100);
  EXPECT_TRUE(ob.set_config_rng);
  EXPECT_EQ(ob.config_rng, o.config_rng);
  EXPECT_EQ(ob.stair_height_m, 0.08);

  // An actor holding both versions gets empty buffers and the versions.
  std::vector<char> light;
  release_to_bytes(w, o, false, false, light);
  EXPECT_LT(light.size(), bytes.size());
  release_from_bytes(light, wb, ob);
  EXPECT_EQ(wb.motion_version, 3u);
  EXPECT_TRUE(wb.motion.empty());
  EXPECT_TRUE(wb.config.empty());
}

}  // namespace
}  // namespace comorph::coopt
