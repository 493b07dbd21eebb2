// The scene-switch rule on synthetic label sequences, and switch delays.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "perception/switch_detector.hpp"

namespace cp = comorph::perception;

namespace {

// `steps` labels of `scene`, except that the last `window` labels before the
// end hold `agree` labels of `other` (the rest `scene`).
std::vector<int> interval_labels(int steps, int window, int scene, int other, int agree) {
  std::vector<int> labels(static_cast<std::size_t>(steps), scene);
  for (int i = 0; i < agree; ++i) labels[static_cast<std::size_t>(steps - window + i)] = other;
  return labels;
}

}  // namespace

TEST(SwitchDetector, VotesNeededIsStrictlyMoreThanAgreement) {
  cp::SwitchDetectorParams p;  // 10 frames, 0.7
  EXPECT_EQ(p.votes_needed(), 8);
  p.agreement = 0.5;
  EXPECT_EQ(p.votes_needed(), 6);
  p.window = 4;
  p.agreement = 0.75;
  EXPECT_EQ(p.votes_needed(), 4);
  p.agreement = 0.0;
  EXPECT_EQ(p.votes_needed(), 1);
  p.window = 3;
  p.agreement = 0.6;  // 1.8 -> 2 votes
  EXPECT_EQ(p.votes_needed(), 2);
}

TEST(SwitchDetector, SevenOfTenIsNotASwitchEightIs) {
  cp::SwitchDetector d({100, 10, 0.7}, 0, 3);
  const std::vector<int> seven = interval_labels(100, 10, 0, 2, 7);
  cp::SwitchDecision last;
  for (const int l : seven) last = d.step(l);
  EXPECT_TRUE(last.evaluated);
  EXPECT_EQ(last.majority, 2);
  EXPECT_EQ(last.votes, 7);
  EXPECT_FALSE(last.switched);
  EXPECT_EQ(d.current_scene(), 0);

  const std::vector<int> eight = interval_labels(100, 10, 0, 2, 8);
  for (const int l : eight) last = d.step(l);
  EXPECT_TRUE(last.evaluated);
  EXPECT_EQ(last.votes, 8);
  EXPECT_TRUE(last.switched);
  EXPECT_EQ(last.scene, 2);
  EXPECT_EQ(d.current_scene(), 2);
  EXPECT_EQ(d.steps(), 200);
}

TEST(SwitchDetector, SwitchesOnlyAtIntervalBoundaries) {
  const cp::SwitchDetectorParams p{100, 10, 0.7};
  cp::SwitchDetector d(p, 0, 3);
  // Scene 1 in every frame from the first step: the window agrees fully from
  // step 10 on, but the decision waits for step 100.
  for (int step = 1; step <= 250; ++step) {
    const bool due = d.evaluates_next();
    const cp::SwitchDecision r = d.step(1);
    EXPECT_EQ(r.evaluated, step % 100 == 0) << "step " << step;
    EXPECT_EQ(due, r.evaluated) << "step " << step;
    EXPECT_EQ(r.switched, step == 100) << "step " << step;
  }
  // Labels changing at arbitrary steps: every declared switch is at a boundary.
  std::vector<int> labels;
  for (int i = 0; i < 2000; ++i) labels.push_back((i / 137) % 3);
  const auto declared = cp::run_detector(p, 0, 3, labels);
  ASSERT_FALSE(declared.empty());
  for (const auto& s : declared) EXPECT_EQ((s.step + 1) % 100, 0) << "switch at index " << s.step;
}

TEST(SwitchDetector, NoSwitchToTheCurrentScene) {
  cp::SwitchDetector d({100, 10, 0.7}, 1, 3);
  for (int step = 0; step < 500; ++step) {
    const cp::SwitchDecision r = d.step(1);
    EXPECT_FALSE(r.switched);
    if (r.evaluated) {
      EXPECT_EQ(r.majority, 1);
      EXPECT_EQ(r.votes, 10);
    }
  }
  EXPECT_EQ(d.current_scene(), 1);
}

TEST(SwitchDetector, UnclassifiedAndMissingFramesCountAgainst) {
  // The window holds 7 labels of class 2 and 3 unclassified frames: 7 of 10,
  // no switch (ignoring the unclassified frames would make it 7 of 7).
  cp::SwitchDetector d({20, 10, 0.7}, 0, 3);
  for (int i = 0; i < 10; ++i) d.step(cp::kNoLabel);
  for (int i = 0; i < 10; ++i) {
    const auto r = d.step(i < 3 ? cp::kNoLabel : 2);
    if (i == 9) {
      EXPECT_TRUE(r.evaluated);
      EXPECT_EQ(r.votes, 7);
      EXPECT_FALSE(r.switched);
    }
  }
  // A window larger than the interval after reset: only 5 labels exist when
  // the first decision comes, 5 of 10 is not > 70 %.
  cp::SwitchDetector e({5, 10, 0.7}, 0, 3);
  cp::SwitchDecision r;
  for (int i = 0; i < 5; ++i) r = e.step(2);
  EXPECT_TRUE(r.evaluated);
  EXPECT_FALSE(r.switched);
  for (int i = 0; i < 5; ++i) r = e.step(2);
  EXPECT_TRUE(r.switched);  // now 10 of 10
}

TEST(SwitchDetector, BatchCallerPushesTheWindowAtTheDecision) {
  // A caller that classifies only when evaluates_next() is true.
  cp::SwitchDetector d({100, 10, 0.7}, 0, 3);
  int switched_at = -1;
  for (int step = 1; step <= 300 && switched_at < 0; ++step) {
    if (d.evaluates_next()) {
      const int label = step > 150 ? 1 : 0;  // the scene changes after step 150
      for (int i = 0; i < 10; ++i) d.push_label(label);
    }
    if (d.step().switched) switched_at = step;
  }
  EXPECT_EQ(switched_at, 200);
}

TEST(SwitchDetector, ResetForgetsLabelsAndSteps) {
  cp::SwitchDetector d({5, 10, 0.7}, 0, 3);
  for (int i = 0; i < 4; ++i) d.step(2);
  d.reset(1);
  EXPECT_EQ(d.steps(), 0);
  EXPECT_EQ(d.current_scene(), 1);
  cp::SwitchDecision r;
  for (int i = 0; i < 5; ++i) r = d.step(2);
  EXPECT_TRUE(r.evaluated);  // the step count restarted: the 5th step decides
  EXPECT_EQ(r.votes, 5);     // the 4 labels before reset() are gone: 5 of 10
  EXPECT_FALSE(r.switched);
}

TEST(SwitchDetector, RejectsBadParametersAndLabels) {
  EXPECT_THROW(cp::SwitchDetector({0, 10, 0.7}, 0, 3), std::invalid_argument);
  EXPECT_THROW(cp::SwitchDetector({100, 0, 0.7}, 0, 3), std::invalid_argument);
  EXPECT_THROW(cp::SwitchDetector({100, 10, 1.0}, 0, 3), std::invalid_argument);
  EXPECT_THROW(cp::SwitchDetector({100, 10, 0.7}, 3, 3), std::invalid_argument);
  cp::SwitchDetector d({100, 10, 0.7}, 0, 3);
  EXPECT_THROW(d.step(3), std::invalid_argument);
  EXPECT_THROW(d.step(-2), std::invalid_argument);
}

TEST(SwitchDelay, PerfectLabelsGiveTheDelayToTheNextBoundary) {
  // Ground truth: stairs for 250 steps, then the target zone; the classifier
  // is perfect. The window of the decision at step 300 is all target zone.
  std::vector<int> truth(600, 0);
  for (std::size_t i = 250; i < truth.size(); ++i) truth[i] = 2;
  const auto changes = cp::scene_changes(truth);
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0].step, 250);
  EXPECT_EQ(changes[0].scene, 2);
  const auto declared = cp::run_detector({100, 10, 0.7}, 0, 3, truth);
  ASSERT_EQ(declared.size(), 1u);
  EXPECT_EQ(declared[0].step, 299);
  const cp::SwitchDelayReport r = cp::switch_delays(changes, declared);
  EXPECT_EQ(r.detected, 1);
  EXPECT_EQ(r.missed, 0);
  EXPECT_EQ(r.false_switches, 0);
  ASSERT_EQ(r.delays.size(), 1u);
  EXPECT_EQ(r.delays[0], 49);
  EXPECT_DOUBLE_EQ(r.mean_delay(), 49.0);

  // A change 5 steps before a decision: only 5 of the 10 frames show it, so
  // the switch waits one more interval.
  std::vector<int> late(400, 0);
  for (std::size_t i = 95; i < late.size(); ++i) late[i] = 1;
  const auto r2 = cp::switch_delays(cp::scene_changes(late), cp::run_detector({100, 10, 0.7}, 0, 3, late));
  ASSERT_EQ(r2.delays.size(), 1u);
  EXPECT_EQ(r2.delays[0], 104);
}

TEST(SwitchDelay, CountsMissedAndFalseSwitches) {
  const std::vector<cp::SceneChange> truth{{100, 1}, {300, 2}, {500, 0}};
  const std::vector<cp::SceneChange> declared{{50, 2},    // before any change to 2: false
                                              {199, 1},   // detects the change at 100
                                              {599, 1}};  // wrong scene after 500: false
  const cp::SwitchDelayReport r = cp::switch_delays(truth, declared);
  EXPECT_EQ(r.detected, 1);
  EXPECT_EQ(r.missed, 2);
  EXPECT_EQ(r.false_switches, 2);
  ASSERT_EQ(r.delays.size(), 1u);
  EXPECT_EQ(r.delays[0], 99);
  EXPECT_TRUE(std::isnan(cp::switch_delays({{10, 1}}, {}).mean_delay()));
}
