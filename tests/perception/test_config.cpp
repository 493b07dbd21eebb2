// configs/perception.yaml and the YAML form of the perception parameters.
#include <gtest/gtest.h>

#include <string>

#include "perception/perception_config.hpp"

namespace cp = comorph::perception;

namespace {
std::string error_of(const std::string& yaml) {
  try {
    cp::perception_config_from_yaml(YAML::Load(yaml), "test.yaml");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(PerceptionConfig, PresetLoadsAndMatchesThePaperRule) {
  const cp::PerceptionConfig c = cp::load_perception_config(COMORPH_CONFIG_DIR "/perception.yaml");
  // The paper's trigger (Sec. II-B): every 100 steps, last 10 frames, > 70 %.
  EXPECT_EQ(c.switch_detector.interval, 100);
  EXPECT_EQ(c.switch_detector.window, 10);
  EXPECT_DOUBLE_EQ(c.switch_detector.agreement, 0.7);
  EXPECT_EQ(c.classifier.classes, static_cast<int>(c.classifier.class_names.size()));
  EXPECT_EQ(c.classifier.validate(), "");
  EXPECT_EQ(c.training.validate(), "");
}

TEST(PerceptionConfig, ReadsValuesAndRejectsBadOnes) {
  const cp::PerceptionConfig c = cp::perception_config_from_yaml(
      YAML::Load("classifier: {width: 32, image_size: 32}\ntraining: {epochs: 3, seed: 9}\n"
                 "switch_detector: {interval: 50}"),
      "test.yaml");
  EXPECT_EQ(c.classifier.width, 32);
  EXPECT_EQ(c.classifier.image_size, 32);
  EXPECT_EQ(c.training.epochs, 3);
  EXPECT_EQ(c.training.seed, 9u);
  EXPECT_EQ(c.switch_detector.interval, 50);
  EXPECT_EQ(c.switch_detector.window, 10);  // untouched keys keep their defaults

  EXPECT_NE(error_of("classifier: {widht: 8}").find("classifier.widht': unknown field"), std::string::npos);
  EXPECT_NE(error_of("bogus: 1").find("'bogus': unknown field"), std::string::npos);
  EXPECT_NE(error_of("switch_detector: {agreement: 1.5}").find("agreement': value 1.5 out of range [0, 1]"),
            std::string::npos);
  EXPECT_NE(error_of("switch_detector: {agreement: 1}").find("agreement must be below 1"), std::string::npos);
  EXPECT_NE(error_of("training: {batch_size: 1}").find("training.batch_size': value 1 out of range [2, 1000000]"),
            std::string::npos);
  EXPECT_NE(error_of("training: {epochs: many}").find("training.epochs': bad value"), std::string::npos);
  EXPECT_NE(error_of("classifier: {classes: 4}").find("class_names has 3 names for 4 classes"),
            std::string::npos);
  EXPECT_NE(error_of("classifier: {image_size: 4}").find("test.yaml"), std::string::npos);
}
