// The fields of RobotParams and SceneParams with their ranges (physical
// sanity bounds) and meanings, and their YAML loaders.
#include <array>
#include <cmath>

#include "sim/params.hpp"
#include "common/yaml_fields.hpp"

namespace comorph::sim {
namespace {

// A depth camera's fields (the module's camera and the decision camera) and
// their ranges, declared once: image size (pixels), field of view (rad), pitch (rad).
void add_camera(YamlFields& f, const std::string& camera, const std::array<const char*, 5>& names, int& width,
                int& height, double& fov_y, double& fov_x, double& pitch) {
  f.add(names[0], &width, 1, 256, "pixels, width of the " + camera + "'s depth image");
  f.add(names[1], &height, 1, 256, "pixels, height of the " + camera + "'s depth image");
  f.add(names[2], &fov_y, 0.05, 3.0, "rad, vertical field of view of the " + camera);
  f.add(names[3], &fov_x, 0.05, 3.0, "rad, horizontal field of view of the " + camera);
  f.add(names[4], &pitch, -1.5, 1.5, "rad, the " + camera + " looks down by this much");
}

}  // namespace

void add_fields(YamlFields& f, RobotParams& p) {
  f.add("module_length", &p.module_length, 0.08, 0.5, "m, front face to back face (body + both plates)");
  f.add("body_height", &p.body_height, 0.04, 0.5, "m, ground to top of the body standing on its wheels");
  f.add("ground_clearance", &p.ground_clearance, 0.0, 0.1, "m, ground to bottom of the body");
  f.add("body_width", &p.body_width, 0.02, 0.5, "m, width of the body");
  f.add("wheel_radius", &p.wheel_radius, 0.01, 0.2, "m, wheel radius");
  f.add("wheel_offset_y", &p.wheel_offset_y, 0.01, 0.5, "m, lateral distance axle centre to wheel centre");
  f.add("plate_thickness", &p.plate_thickness, 0.002, 0.05, "m, each connecting plate (2 per module)");
  f.add("plate_bottom", &p.plate_bottom, 0.0, 0.3, "m above ground, the plates' lower edge");
  f.add("plate_top", &p.plate_top, 0.01, 0.5, "m above ground, the plates' upper edge");
  f.add("body_mass", &p.body_mass, 0.01, 20, "kg, body with electronics, battery and motors");
  f.add("wheel_mass", &p.wheel_mass, 0.001, 5, "kg, each wheel");
  f.add("plate_mass", &p.plate_mass, 0.001, 5, "kg, each plate");
  f.add("wheel_kv", &p.wheel_kv, 1e-4, 100, "N m s/rad, velocity gain of the wheel servos");
  f.add("wheel_max_torque", &p.wheel_max_torque, 1e-3, 100, "N m, wheel motor torque limit");
  f.add("wheel_max_speed", &p.wheel_max_speed, 0.1, 200, "rad/s, wheel speed limit");
  f.add("wheel_armature", &p.wheel_armature, 0, 1, "kg m^2, reflected gear-motor inertia of a wheel");
  f.add("hinge_kp", &p.hinge_kp, 1e-3, 1e4, "N m/rad, position gain of the plate hinges");
  f.add("hinge_kv", &p.hinge_kv, 0, 1e3, "N m s/rad, velocity gain of the plate hinges");
  f.add("hinge_max_torque", &p.hinge_max_torque, 1e-3, 1e3, "N m, hinge motor torque limit");
  f.add("hinge_range", &p.hinge_range, 0.01, 3.1, "rad, symmetric hinge joint limit");
  f.add("hinge_armature", &p.hinge_armature, 0, 1, "kg m^2, reflected inertia of a hinge motor");
  f.add("hinge_damping", &p.hinge_damping, 0, 100, "N m s/rad, passive hinge damping");
  f.add("friction", &p.friction, 0.05, 3, "sliding friction coefficient of wheels and ground");
  add_camera(f, "motion camera", {"depth_width", "depth_height", "depth_fov_y", "depth_fov_x", "depth_pitch"},
             p.depth_width, p.depth_height, p.depth_fov_y, p.depth_fov_x, p.depth_pitch);
  f.add("depth_max_range", &p.depth_max_range, 0.1, 100, "m, depth 1.0 at this distance (values clipped to [0.01, 1])");
  add_camera(f, "decision camera",
             {"decision_depth_width", "decision_depth_height", "decision_fov_y", "decision_fov_x", "decision_pitch"},
             p.decision_depth_width, p.decision_depth_height, p.decision_fov_y, p.decision_fov_x, p.decision_pitch);
  f.add("scan_columns", &p.scan_columns, 0, 256,
        "rays of the level obstacle scan, the motion model's clearance row; 0 = from the depth image");
  f.add("scan_fov_x", &p.scan_fov_x, 0.05, 6.28, "rad, total angle of the obstacle scan, centred on the heading");
  f.add("camera_height", &p.camera_height, 0.0, 1.0, "m above ground of the cameras, at module 1's front face");
  f.add("distance_range", &p.distance_range, 0.05, 20, "m, the left/right distance sensors saturate here");
  f.add("distance_height", &p.distance_height, 0.0, 1.0, "m above ground of the distance sensors");
  f.add("battery_capacity", &p.battery_capacity, 1, 1e7, "J per module");
  f.add("idle_power", &p.idle_power, 0, 1000, "W per module: electronics, radio, camera");
  f.add("motor_efficiency", &p.motor_efficiency, 0.01, 1, "mechanical / electrical power of a motor");
  f.add("copper_loss", &p.copper_loss, 0, 1000, "W per (N m)^2 of motor torque");
  f.add("physics_timestep", &p.physics_timestep, 1e-4, 0.01, "s, MuJoCo's time step");
  f.add("control_period", &p.control_period, 1e-3, 1.0, "s between control steps (a multiple of physics_timestep)");
}

void add_fields(YamlFields& f, SceneParams& p) {
  f.add("start_gap", &p.start_gap, 0.05, 5, "m, robot front to the first riser");
  f.add("steps", &p.steps, 1, 6, "steps of the stairs (the last one is the flat area)");
  f.add("tread", &p.tread, 0.1, 3, "m, depth of each step before the flat area");
  f.add("stair_width", &p.stair_width, 0.3, 10, "m, width of the stairs (no side walls)");
  f.add("stair_height_a", &p.stair_height_a, 0.0, 0.3, "m, first of the three stair heights drawn per episode");
  f.add("stair_height_b", &p.stair_height_b, 0.0, 0.3, "m, second stair height (may repeat another)");
  f.add("stair_height_c", &p.stair_height_c, 0.0, 0.3, "m, third stair height (may repeat another)");
  f.add("area_length", &p.area_length, 1, 50, "m, flat area along x");
  f.add("area_width", &p.area_width, 1, 50, "m, flat area along y");
  f.add("obstacle_region_start", &p.obstacle_region_start, 0, 40, "m from the flat area's near edge");
  f.add("obstacle_region_length", &p.obstacle_region_length, 0.3, 40, "m along x (the region is area_width wide)");
  f.add("obstacle_size", &p.obstacle_size, 0.02, 2, "m, side of an obstacle's square footprint");
  f.add("obstacle_height", &p.obstacle_height, 0.02, 2, "m, obstacle height");
  f.add("obstacles", &p.obstacles, 0, 50, "obstacles on the flat area (K: 6 to train, 7 and 8 to test)");
  f.add("max_obstacles", &p.max_obstacles, 0, 50, "obstacle slots compiled into every model");
  f.add("mixed_on_stairs", &p.mixed_on_stairs, 0, 10, "obstacles put on the treads in the mixed scenario");
  f.add("target_margin", &p.target_margin, 0.1, 20, "m, target x = the flat area's far edge - this");
  f.add("target_lateral", &p.target_lateral, 0, 20, "m, target y uniform in [-this, this]");
  f.add("target_radius", &p.target_radius, 0.05, 5, "m, reached when module 1 is this close (horizontally)");
  f.add("path_clearance", &p.path_clearance, 0, 2, "m, the free-path check inflates obstacles by this");
  f.add("start_lateral_noise", &p.start_lateral_noise, 0, 1, "m, seeded start offset in y");
  f.add("start_yaw_noise", &p.start_yaw_noise, 0, 1, "rad, seeded start heading noise");
  f.add("target_zone_distance", &p.target_zone_distance, 0, 20, "m, the scene label is the target's within this");
}

void check_fields(const YamlFields& f, const RobotParams& p) {
  const double ratio = p.control_period / p.physics_timestep;
  if (std::abs(ratio - std::round(ratio)) > 1e-6)
    f.fail("control_period", "must be a whole multiple of physics_timestep");
  if (p.plate_top <= p.plate_bottom) f.fail("plate_top", "must be above plate_bottom");
  if (p.ground_clearance >= p.body_height) f.fail("ground_clearance", "must be below body_height");
}

void check_fields(const YamlFields& f, const SceneParams& p) {
  if (p.obstacles > p.max_obstacles) f.fail("obstacles", "exceeds max_obstacles");
  if (p.obstacle_region_start + p.obstacle_region_length > p.area_length)
    f.fail("obstacle_region_length", "region extends past the flat area");
}

RobotParams robot_params_from_yaml(const std::string& text, const std::string& source, RobotParams p) {
  YamlFields f(source);
  add_fields(f, p);
  f.apply_text(text);
  check_fields(f, p);
  return p;
}

SceneParams scene_params_from_yaml(const std::string& text, const std::string& source, SceneParams p) {
  YamlFields f(source);
  add_fields(f, p);
  f.apply_text(text);
  check_fields(f, p);
  return p;
}

RobotParams load_robot_params(const std::string& path, RobotParams defaults) {
  return robot_params_from_yaml(read_text_file(path), path, defaults);
}
SceneParams load_scene_params(const std::string& path, SceneParams defaults) {
  return scene_params_from_yaml(read_text_file(path), path, defaults);
}

}  // namespace comorph::sim
