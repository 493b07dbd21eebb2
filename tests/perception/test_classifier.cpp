// The ResNet-18 scene classifier: it learns a synthetic depth task that a
// broken net (or shuffled labels) cannot; save/load; determinism; the
// perception loop. One intra-op thread throughout (bit-exact results).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

#include "perception/scene_classifier.hpp"
#include "perception/scene_monitor.hpp"
#include "perception/switch_evaluation.hpp"
#include "perception/synthetic.hpp"
#include "perception/training.hpp"

namespace cp = comorph::perception;
namespace fs = std::filesystem;

namespace {

std::string temp_dir(const std::string& name) {
  return (fs::temp_directory_path() /
          ("comorph_test_perception_" + std::to_string(::getpid())) / name)
      .string();
}

cp::ClassifierParams small_net() {
  cp::ClassifierParams p;
  p.width = 8;  // a narrow ResNet-18: 0.18 M weights, trains in seconds
  return p;
}

cp::TrainParams quick_training() {
  cp::TrainParams t;
  t.epochs = 6;
  t.batch_size = 32;
  t.learning_rate = 3e-3;
  t.seed = 3;
  t.progress = false;
  return t;
}

cp::Dataset synthetic(int count, std::uint64_t seed) {
  cp::SyntheticParams s;
  s.count = count;
  s.seed = seed;
  return cp::make_synthetic_dataset(s);
}

// One trained model shared by the tests that need one (trained once).
class TrainedClassifier : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    cp::SceneClassifier::set_threads(1);
    train_ = std::make_unique<cp::Dataset>(synthetic(600, 11));
    held_out_ = std::make_unique<cp::Dataset>(synthetic(300, 12));
    result_ = std::make_unique<cp::TrainResult>(
        cp::train_classifier(*train_, small_net(), quick_training(), held_out_.get()));
  }
  static void TearDownTestSuite() {
    result_.reset();
    train_.reset();
    held_out_.reset();
  }
  static std::unique_ptr<cp::Dataset> train_, held_out_;
  static std::unique_ptr<cp::TrainResult> result_;
};
std::unique_ptr<cp::Dataset> TrainedClassifier::train_, TrainedClassifier::held_out_;
std::unique_ptr<cp::TrainResult> TrainedClassifier::result_;

}  // namespace

TEST_F(TrainedClassifier, LearnsTheSyntheticDepthTask) {
  const cp::TrainResult& r = *result_;
  ASSERT_EQ(r.epochs.size(), 6u);
  EXPECT_EQ(r.train_count, 600u);
  EXPECT_EQ(r.eval_count, 300u);
  EXPECT_LT(r.epochs.back().train_loss, r.epochs.front().train_loss);
  EXPECT_GT(r.eval.accuracy, 0.90);
  std::cout << cp::format_evaluation(r.eval, small_net());
  // The confusion matrix accounts for every held-out image, per true class.
  std::int64_t total = 0;
  for (std::size_t t = 0; t < r.eval.confusion.size(); ++t) {
    std::int64_t row = 0;
    for (const auto v : r.eval.confusion[t]) row += v;
    EXPECT_EQ(row, 100) << "true class " << t;
    total += row;
  }
  EXPECT_EQ(total, 300);
  // evaluate_classifier agrees with the training loop's final evaluation.
  const cp::EvalResult again = cp::evaluate_classifier(result_->model, *held_out_);
  EXPECT_EQ(again.confusion, r.eval.confusion);
}

TEST(Classifier, ShuffledLabelsStayNearChance) {
  // The same net and budget on labels that carry no information: held-out
  // accuracy must stay near 1/3 (a leak between images and labels, or an
  // evaluation bug, would show up here).
  cp::SceneClassifier::set_threads(1);
  cp::Dataset train = synthetic(600, 11);
  std::mt19937 rng(5);
  std::shuffle(train.labels.begin(), train.labels.end(), rng);
  const cp::Dataset held_out = synthetic(300, 12);
  const cp::TrainResult r = cp::train_classifier(train, small_net(), quick_training(), &held_out);
  EXPECT_LT(r.eval.accuracy, 0.50);
  std::cout << cp::format_evaluation(r.eval, small_net());
  EXPECT_GT(r.eval.accuracy, 0.15);
}

TEST_F(TrainedClassifier, SaveLoadGivesIdenticalLogits) {
  const std::string dir = temp_dir("roundtrip");
  result_->model.save(dir);
  EXPECT_TRUE(fs::exists(fs::path(dir) / "classifier.pt"));
  EXPECT_TRUE(fs::exists(fs::path(dir) / "classifier.yaml"));
  const cp::ClassifierParams expected = small_net();
  cp::SceneClassifier loaded = cp::SceneClassifier::load(dir, &expected);
  EXPECT_EQ(loaded.params().width, 8);
  EXPECT_EQ(loaded.params().class_names, expected.class_names);

  const int n = 20, k = 3;
  std::vector<float> a(n * k), b(n * k);
  result_->model.logits(held_out_->image(0), n, 16, 16, a.data());
  loaded.logits(held_out_->image(0), n, 16, 16, b.data());
  EXPECT_EQ(a, b);
  EXPECT_EQ(loaded.flat_parameters(), result_->model.flat_parameters());
}

TEST_F(TrainedClassifier, MismatchedSidecarOrExpectationErrors) {
  const std::string dir = temp_dir("mismatch");
  result_->model.save(dir);
  // Expected settings differ from the sidecar.
  cp::ClassifierParams wider = small_net();
  wider.width = 16;
  try {
    cp::SceneClassifier::load(dir, &wider);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("width 8 does not match the expected 16"), std::string::npos)
        << e.what();
  }
  // A sidecar edited to another width than the weights were saved with.
  const fs::path sidecar = fs::path(dir) / "classifier.yaml";
  std::ifstream in(sidecar);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();
  const auto pos = text.find("width: 8");
  ASSERT_NE(pos, std::string::npos) << text;
  text.replace(pos, 8, "width: 16");
  std::ofstream(sidecar) << text;
  try {
    cp::SceneClassifier::load(dir);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("classifier.pt"), std::string::npos) << e.what();
  }
  EXPECT_THROW(cp::SceneClassifier::load(temp_dir("no_such_model")), std::runtime_error);
}

TEST_F(TrainedClassifier, BatchAndSingleClassificationAgree) {
  const int n = 10;
  std::vector<int> batch(n);
  result_->model.classify_batch(held_out_->image(0), n, 16, 16, batch.data());
  std::vector<float> logits(n * 3);
  result_->model.logits(held_out_->image(0), n, 16, 16, logits.data());
  for (int i = 0; i < n; ++i) {
    EXPECT_EQ(result_->model.classify(held_out_->image(static_cast<std::size_t>(i)), 16, 16), batch[i]);
    const auto* row = logits.data() + 3 * i;
    EXPECT_EQ(static_cast<int>(std::max_element(row, row + 3) - row), batch[i]);
  }
  EXPECT_THROW(result_->model.classify(held_out_->image(0), 8, 8), std::invalid_argument);
}

TEST_F(TrainedClassifier, MonitorDeclaresTheSceneChange) {
  // 250 control steps of stairs frames, then target-zone frames: the monitor
  // classifies its last 10 frames every 100 steps and switches at step 300
  // (delay 50 steps) when the classifier is right on those frames.
  cp::SceneMonitor monitor(result_->model, {100, 10, 0.7}, cp::kStairs);
  const cp::Dataset frames = synthetic(600, 21);  // labels cycle 0, 1, 2
  std::vector<int> truth;
  std::vector<cp::SceneChange> declared;
  int stairs = 0, target = 2;
  for (int step = 0; step < 500; ++step) {
    const bool before = step < 250;
    const std::size_t index = before ? static_cast<std::size_t>(3 * (stairs++ % 200))
                                     : static_cast<std::size_t>(3 * (target++ % 200) + 2);
    truth.push_back(before ? cp::kStairs : cp::kTargetZone);
    const cp::SwitchDecision d = monitor.step(frames.image(index));
    if (d.switched) declared.push_back({step, d.scene});
  }
  EXPECT_EQ(monitor.current_scene(), cp::kTargetZone);
  const cp::SwitchDelayReport r = cp::switch_delays(cp::scene_changes(truth), declared);
  EXPECT_EQ(r.detected, 1);
  EXPECT_EQ(r.false_switches, 0);
  ASSERT_EQ(r.delays.size(), 1u);
  EXPECT_EQ(r.delays[0], 49);  // switch at step index 299
  EXPECT_EQ(monitor.last_labels().size(), 10u);
}

TEST(Classifier, SameSeedSameWeights) {
  cp::SceneClassifier::set_threads(1);
  const cp::Dataset data = synthetic(150, 31);
  cp::TrainParams t = quick_training();
  t.epochs = 2;
  const cp::TrainResult a = cp::train_classifier(data, small_net(), t);
  const cp::TrainResult b = cp::train_classifier(data, small_net(), t);
  EXPECT_EQ(a.model.flat_parameters(), b.model.flat_parameters());
  EXPECT_EQ(a.eval_count, 30u);  // eval_fraction 0.2 held out of 150
  t.seed = 4;
  const cp::TrainResult c = cp::train_classifier(data, small_net(), t);
  EXPECT_NE(a.model.flat_parameters(), c.model.flat_parameters());
}

TEST(Classifier, RejectsDataThatDoesNotFit) {
  cp::TrainParams t = quick_training();
  t.epochs = 1;
  cp::SyntheticParams s;
  s.count = 30;
  s.image_size = 12;
  const cp::Dataset wrong_size = cp::make_synthetic_dataset(s);
  EXPECT_THROW(cp::train_classifier(wrong_size, small_net(), t), std::invalid_argument);
  cp::ClassifierParams four = small_net();
  four.classes = 4;
  four.class_names.clear();
  EXPECT_THROW(cp::train_classifier(synthetic(30, 1), four, t), std::invalid_argument);
  EXPECT_THROW(cp::train_classifier(cp::Dataset(16, 16, 3), small_net(), t), std::invalid_argument);
  cp::ClassifierParams bad = small_net();
  bad.device = "toaster";
  EXPECT_THROW(cp::SceneClassifier{bad}, std::invalid_argument);
  // A CUDA device this machine does not have: refused when the classifier is made.
  bad.device = "cuda:7";
  try {
    cp::SceneClassifier c{bad};
    ADD_FAILURE() << "made a classifier on cuda:7";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("torch device 'cuda:7' is not available here"), std::string::npos) << e.what();
  }
}

TEST_F(TrainedClassifier, SwitchTrialsDetectTheChangesWithinTwoIntervals) {
  cp::SwitchTrialParams t;
  t.trials = 20;
  t.seed = 5;
  const cp::SwitchTrialReport r = cp::evaluate_switching(result_->model, *held_out_, {100, 10, 0.7}, t);
  EXPECT_EQ(r.trials, 20);
  EXPECT_EQ(r.delays.detected + r.delays.missed, 20);
  EXPECT_GE(r.delays.detected, 18);
  EXPECT_LE(r.delays.false_switches, 2);
  // A change is seen at the next decision (< 100 steps) or, when the window
  // straddles it, the one after (< 200 steps).
  EXPECT_GE(r.delays.mean_delay(), 0.0);
  EXPECT_LT(r.max_delay, 200.0);
  std::cout << cp::format_switch_report(r);
}
