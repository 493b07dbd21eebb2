// Config files: every field loads, unknown keys and bad values name file and field.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "sim/params.hpp"
#include "support/test_support.hpp"

using namespace comorph::sim;

using comorph::test_support::error_of;

TEST(Params, RepositoryConfigsLoadAndMatchTheDefaults) {
  const std::string dir = std::string(COMORPH_SOURCE_DIR) + "/configs/sim/";
  const RobotParams r = load_robot_params(dir + "robot.yaml");
  const RobotParams d;
  EXPECT_EQ(r.module_length, d.module_length);
  EXPECT_EQ(r.idle_power, d.idle_power);
  EXPECT_EQ(r.hinge_max_torque, d.hinge_max_torque);
  EXPECT_EQ(r.depth_width, d.depth_width);
  const SceneParams s = load_scene_params(dir + "scene.yaml");
  EXPECT_EQ(s.obstacles, SceneParams{}.obstacles);
  EXPECT_EQ(s.target_radius, SceneParams{}.target_radius);
}

TEST(Params, FieldsAreRead) {
  const RobotParams r = robot_params_from_yaml("wheel_radius: 0.05\ndepth_width: 32\n", "x.yaml");
  EXPECT_EQ(r.wheel_radius, 0.05);
  EXPECT_EQ(r.depth_width, 32);
  const SceneParams s = scene_params_from_yaml("obstacles: 8\ntread: 0.5\n", "s.yaml");
  EXPECT_EQ(s.obstacles, 8);
  EXPECT_EQ(s.tread, 0.5);
}

TEST(Params, ErrorsNameTheFileAndTheField) {
  std::string e = error_of([] { robot_params_from_yaml("wheel_radios: 0.05\n", "robot.yaml"); });
  EXPECT_NE(e.find("robot.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("wheel_radios"), std::string::npos) << e;
  EXPECT_NE(e.find("unknown"), std::string::npos) << e;

  e = error_of([] { robot_params_from_yaml("friction: -1\n", "robot.yaml"); });
  EXPECT_NE(e.find("'friction'"), std::string::npos) << e;
  EXPECT_NE(e.find("out of range"), std::string::npos) << e;

  e = error_of([] { scene_params_from_yaml("obstacles: many\n", "scene.yaml"); });
  EXPECT_NE(e.find("scene.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("'obstacles'"), std::string::npos) << e;

  e = error_of([] { robot_params_from_yaml("control_period: 0.033\n", "robot.yaml"); });
  EXPECT_NE(e.find("control_period"), std::string::npos) << e;

  e = error_of([] { scene_params_from_yaml("obstacles: [1\n", "scene.yaml"); });
  EXPECT_NE(e.find("scene.yaml"), std::string::npos) << e;

  e = error_of([] { load_robot_params("/nonexistent/robot.yaml"); });
  EXPECT_NE(e.find("/nonexistent/robot.yaml"), std::string::npos) << e;
}
