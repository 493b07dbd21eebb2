// YAML loaders of RobotParams and SceneParams (ranges are physical sanity bounds).
#include <array>
#include <cmath>

#include "sim/params.hpp"
#include "common/yaml_fields.hpp"

namespace comorph::sim {
namespace {

// A depth camera's fields (the module's camera and the decision camera) and
// their ranges, declared once: image size (pixels), field of view (rad), pitch (rad).
void add_camera(YamlFields& f, const std::array<const char*, 5>& names, int& width, int& height, double& fov_y,
                double& fov_x, double& pitch) {
  f.add(names[0], &width, 1, 256);
  f.add(names[1], &height, 1, 256);
  f.add(names[2], &fov_y, 0.05, 3.0);
  f.add(names[3], &fov_x, 0.05, 3.0);
  f.add(names[4], &pitch, -1.5, 1.5);
}

}  // namespace

RobotParams robot_params_from_yaml(const std::string& text, const std::string& source,
                                   RobotParams p) {
  YamlFields f(source);
  f.add("module_length", &p.module_length, 0.08, 0.5);
  f.add("body_height", &p.body_height, 0.04, 0.5);
  f.add("ground_clearance", &p.ground_clearance, 0.0, 0.1);
  f.add("body_width", &p.body_width, 0.02, 0.5);
  f.add("wheel_radius", &p.wheel_radius, 0.01, 0.2);
  f.add("wheel_offset_y", &p.wheel_offset_y, 0.01, 0.5);
  f.add("plate_thickness", &p.plate_thickness, 0.002, 0.05);
  f.add("plate_bottom", &p.plate_bottom, 0.0, 0.3);
  f.add("plate_top", &p.plate_top, 0.01, 0.5);
  f.add("body_mass", &p.body_mass, 0.01, 20);
  f.add("wheel_mass", &p.wheel_mass, 0.001, 5);
  f.add("plate_mass", &p.plate_mass, 0.001, 5);
  f.add("wheel_kv", &p.wheel_kv, 1e-4, 100);
  f.add("wheel_max_torque", &p.wheel_max_torque, 1e-3, 100);
  f.add("wheel_max_speed", &p.wheel_max_speed, 0.1, 200);
  f.add("wheel_armature", &p.wheel_armature, 0, 1);
  f.add("hinge_kp", &p.hinge_kp, 1e-3, 1e4);
  f.add("hinge_kv", &p.hinge_kv, 0, 1e3);
  f.add("hinge_max_torque", &p.hinge_max_torque, 1e-3, 1e3);
  f.add("hinge_range", &p.hinge_range, 0.01, 3.1);
  f.add("hinge_armature", &p.hinge_armature, 0, 1);
  f.add("hinge_damping", &p.hinge_damping, 0, 100);
  f.add("friction", &p.friction, 0.05, 3);
  add_camera(f, {"depth_width", "depth_height", "depth_fov_y", "depth_fov_x", "depth_pitch"}, p.depth_width,
             p.depth_height, p.depth_fov_y, p.depth_fov_x, p.depth_pitch);
  f.add("depth_max_range", &p.depth_max_range, 0.1, 100);
  add_camera(f, {"decision_depth_width", "decision_depth_height", "decision_fov_y", "decision_fov_x", "decision_pitch"},
             p.decision_depth_width, p.decision_depth_height, p.decision_fov_y, p.decision_fov_x, p.decision_pitch);
  f.add("scan_columns", &p.scan_columns, 0, 256);
  f.add("scan_fov_x", &p.scan_fov_x, 0.05, 6.28);
  f.add("camera_height", &p.camera_height, 0.0, 1.0);
  f.add("distance_range", &p.distance_range, 0.05, 20);
  f.add("distance_height", &p.distance_height, 0.0, 1.0);
  f.add("battery_capacity", &p.battery_capacity, 1, 1e7);
  f.add("idle_power", &p.idle_power, 0, 1000);
  f.add("motor_efficiency", &p.motor_efficiency, 0.01, 1);
  f.add("copper_loss", &p.copper_loss, 0, 1000);
  f.add("physics_timestep", &p.physics_timestep, 1e-4, 0.01);
  f.add("control_period", &p.control_period, 1e-3, 1.0);
  f.apply_text(text);
  const double ratio = p.control_period / p.physics_timestep;
  if (std::abs(ratio - std::round(ratio)) > 1e-6)
    f.fail("control_period", "must be a whole multiple of physics_timestep");
  if (p.plate_top <= p.plate_bottom) f.fail("plate_top", "must be above plate_bottom");
  if (p.ground_clearance >= p.body_height) f.fail("ground_clearance", "must be below body_height");
  return p;
}

SceneParams scene_params_from_yaml(const std::string& text, const std::string& source,
                                   SceneParams p) {
  YamlFields f(source);
  f.add("start_gap", &p.start_gap, 0.05, 5);
  f.add("steps", &p.steps, 1, 6);
  f.add("tread", &p.tread, 0.1, 3);
  f.add("stair_width", &p.stair_width, 0.3, 10);
  f.add("stair_height_a", &p.stair_height_a, 0.0, 0.3);
  f.add("stair_height_b", &p.stair_height_b, 0.0, 0.3);
  f.add("stair_height_c", &p.stair_height_c, 0.0, 0.3);
  f.add("area_length", &p.area_length, 1, 50);
  f.add("area_width", &p.area_width, 1, 50);
  f.add("obstacle_region_start", &p.obstacle_region_start, 0, 40);
  f.add("obstacle_region_length", &p.obstacle_region_length, 0.3, 40);
  f.add("obstacle_size", &p.obstacle_size, 0.02, 2);
  f.add("obstacle_height", &p.obstacle_height, 0.02, 2);
  f.add("obstacles", &p.obstacles, 0, 50);
  f.add("max_obstacles", &p.max_obstacles, 0, 50);
  f.add("mixed_on_stairs", &p.mixed_on_stairs, 0, 10);
  f.add("target_margin", &p.target_margin, 0.1, 20);
  f.add("target_lateral", &p.target_lateral, 0, 20);
  f.add("target_radius", &p.target_radius, 0.05, 5);
  f.add("path_clearance", &p.path_clearance, 0, 2);
  f.add("start_lateral_noise", &p.start_lateral_noise, 0, 1);
  f.add("start_yaw_noise", &p.start_yaw_noise, 0, 1);
  f.add("target_zone_distance", &p.target_zone_distance, 0, 20);
  f.apply_text(text);
  if (p.obstacles > p.max_obstacles) f.fail("obstacles", "exceeds max_obstacles");
  if (p.obstacle_region_start + p.obstacle_region_length > p.area_length)
    f.fail("obstacle_region_length", "region extends past the flat area");
  return p;
}

RobotParams load_robot_params(const std::string& path, RobotParams defaults) {
  return robot_params_from_yaml(read_text_file(path), path, defaults);
}
SceneParams load_scene_params(const std::string& path, SceneParams defaults) {
  return scene_params_from_yaml(read_text_file(path), path, defaults);
}

}  // namespace comorph::sim
