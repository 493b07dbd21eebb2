// Parameters of the simulated robot and of the scenario. Every field has its
// unit; the defaults are the tuned values documented in docs/sim.md and are
// mirrored in configs/robot.yaml and configs/scene.yaml.
#pragma once

#include <array>
#include <string>

namespace comorph {
class YamlFields;
}

namespace comorph::sim {

// One YaMoR-like module (paper Fig. 7) and the chain built from it.
// Module frame: x forward along the chain, y left, z up, origin on the wheel axle.
struct RobotParams {
  // ---- geometry ----
  double module_length = 0.16;     // m, front face to back face (body + both plates)
  double body_height = 0.12;       // m, ground to top of the body when standing on its wheels
  double ground_clearance = 0.03;  // m, ground to bottom of the body
  double body_width = 0.10;        // m
  double wheel_radius = 0.06;      // m
  double wheel_offset_y = 0.09;    // m, lateral distance axle centre -> wheel centre
  double plate_thickness = 0.02;   // m, each connecting plate (2 per module)
  double plate_bottom = 0.05;      // m above ground: plates sit high, wheels meet a riser first
  double plate_top = 0.11;         // m above ground
  // ---- mass ----
  double body_mass = 0.60;   // kg (electronics, battery, motors)
  double wheel_mass = 0.08;  // kg each
  double plate_mass = 0.05;  // kg each
  // ---- wheel motors: velocity servos ----
  double wheel_kv = 0.5;          // N m s/rad, velocity gain
  double wheel_max_torque = 0.8;  // N m
  double wheel_max_speed = 8.0;   // rad/s, ctrlrange
  double wheel_armature = 0.002;  // kg m^2, reflected gear-motor inertia (also keeps Euler stable)
  // ---- plate hinges ("z-axis motors"): position servos ----
  double hinge_kp = 20.0;          // N m/rad
  double hinge_kv = 0.5;           // N m s/rad
  double hinge_max_torque = 3.0;   // N m
  double hinge_range = 1.0;        // rad, symmetric joint limit
  double hinge_armature = 0.002;   // kg m^2
  double hinge_damping = 0.05;     // N m s/rad, passive
  // ---- contact ----
  double friction = 1.0;  // sliding friction coefficient of wheels and ground (rubber on wood)
  // ---- sensors ----
  int depth_width = 16;           // pixels
  int depth_height = 16;          // pixels
  double depth_fov_y = 1.0;       // rad, vertical field of view
  double depth_fov_x = 1.2;       // rad, horizontal field of view
  double depth_pitch = 0.25;      // rad, camera looks down by this much
  double depth_max_range = 4.0;   // m, depth 1.0 at this distance; values clipped to [0.01, 1]
  double camera_height = 0.11;    // m above ground, at module 1's front face
  // Decision camera: the same camera position, read only when the configuration
  // model decides (2-3 times an episode). Narrower and aimed at the stairs, so
  // that 0.02 m of stair height is several rows, not one (at the start the first
  // riser is 0.5 m away: its top edge is 0.04 rad lower per 0.02 m of height).
  int decision_depth_width = 32;      // pixels
  int decision_depth_height = 32;     // pixels
  double decision_fov_y = 0.45;       // rad, vertical field of view
  double decision_fov_x = 0.9;        // rad, horizontal field of view
  double decision_pitch = 0.03;       // rad, looks down by this much
  // Obstacle scan: a level fan of rays from the camera position, every control
  // step (a ring of range sensors, or a planar lidar). With scan_columns > 0 it
  // is the clearance row the motion model reads (task::MultiTaskEnv::clearance);
  // 0 = the clearance row comes from the depth image's rows above the horizon.
  // Why wider than the camera: an obstacle the robot turns away from leaves a
  // 1.2 rad view while it is still in the way, and a model without memory then
  // turns back into it.
  int scan_columns = 0;               // rays, uniform in angle, column 0 at the left
  double scan_fov_x = 3.0;            // rad, the fan's total angle, centred on module 1's heading
  double distance_range = 1.0;    // m, left/right distance sensors saturate at 1.0 here
  double distance_height = 0.08;  // m above ground
  // ---- energy ----
  double battery_capacity = 20000.0;  // J per module
  double idle_power = 20.0;           // W per module: electronics, radio, camera share (calibrated, docs/sim.md)
  double motor_efficiency = 0.6;      // mechanical / electrical power of a motor
  double copper_loss = 3.0;           // W per (N m)^2 of motor torque (holding costs too)
  // ---- timing ----
  double physics_timestep = 0.002;  // s
  double control_period = 0.032;    // s (a multiple of physics_timestep)
};

// The multi-task scenario (paper Fig. 8). Scene frame: x towards the target,
// z up, the first riser at x = 0, the robot's front face starts at x = -start_gap.
struct SceneParams {
  double start_gap = 0.5;         // m, robot front -> first riser
  int steps = 3;                  // number of steps (the last one is the flat area)
  double tread = 0.4;             // m, depth of each step before the flat area
  double stair_width = 2.0;       // m, no side walls
  double stair_height_a = 0.04;   // m, the three heights drawn per episode
  double stair_height_b = 0.06;   // m
  double stair_height_c = 0.08;   // m
  double area_length = 6.0;       // m, flat area along x
  double area_width = 6.0;        // m, flat area along y
  double obstacle_region_start = 1.0;   // m from the flat area's near edge
  double obstacle_region_length = 3.0;  // m along x (region is area_width x this)
  double obstacle_size = 0.3;     // m, square footprint side
  double obstacle_height = 0.4;   // m
  int obstacles = 6;              // K (6 to train, 7 and 8 to test)
  int max_obstacles = 10;         // slots compiled into every model
  int mixed_on_stairs = 2;        // obstacles put on the treads in the "mixed" variant
  double target_margin = 1.0;     // m, target x = far edge - this
  double target_lateral = 2.0;    // m, target y uniform in [-this, this]
  double target_radius = 0.3;     // m, reached when module 1 is this close (horizontal)
  double path_clearance = 0.22;   // m, free-path check: obstacle inflated by this
  double start_lateral_noise = 0.05;  // m, seeded start offset in y
  double start_yaw_noise = 0.05;      // rad, seeded start heading noise
  double target_zone_distance = 1.5;  // m, scene label 2 within this of the target

  // The heights an episode draws from (one of the three, uniformly; they may repeat).
  std::array<double, 3> stair_heights() const { return {stair_height_a, stair_height_b, stair_height_c}; }
};

// Every field of RobotParams / SceneParams with its range and meaning (for
// reading, `comorph config keys` and a run's resolved config).
void add_fields(YamlFields& f, RobotParams& p);
void add_fields(YamlFields& f, SceneParams& p);
// What the ranges cannot say (a control period that is a multiple of the
// time step, ...); throws through f.fail.
void check_fields(const YamlFields& f, const RobotParams& p);
void check_fields(const YamlFields& f, const SceneParams& p);

// Loads a YAML file of fields of RobotParams / SceneParams. Missing fields keep
// their defaults; unknown fields and out-of-range values throw
// std::runtime_error naming the file and the field.
RobotParams load_robot_params(const std::string& path, RobotParams defaults = {});
SceneParams load_scene_params(const std::string& path, SceneParams defaults = {});
// The same from YAML text (source_name appears in error messages).
RobotParams robot_params_from_yaml(const std::string& text, const std::string& source_name,
                                   RobotParams defaults = {});
SceneParams scene_params_from_yaml(const std::string& text, const std::string& source_name,
                                   SceneParams defaults = {});

}  // namespace comorph::sim
