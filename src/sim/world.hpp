// The simulated world of one episode: the robot of a configuration in a seeded
// scene. Read-only compiled models come from a ModelCache; the World keeps its
// own copy per configuration (the scene written into it at reset) and one
// mjData per configuration, so reset() and reconfigure() never recompile and
// the control step never allocates.
#pragma once

#include <mujoco/mujoco.h>

#include <array>
#include <memory>
#include <vector>

#include "morphology/configuration.hpp"
#include "sim/model.hpp"
#include "sim/params.hpp"
#include "sim/scene.hpp"

namespace comorph::sim {

// Why the physics was declared unstable (0 = stable).
enum class Instability { none, nan_state, bad_qacc, bad_qpos, bad_qvel };

// Outcome of one control period of physics.
struct PhysicsStepInfo {
  bool obstacle_contact = false;  // any robot geom touched an obstacle during the period
  bool stair_contact = false;     // any robot geom touched a riser/step (informational)
  Instability instability = Instability::none;
  double energy_J = 0;            // electrical energy drawn by all modules in the period
};

class World {
 public:
  World(const RobotParams& robot, const SceneParams& scene, std::shared_ptr<ModelCache> cache = nullptr);

  // New episode: writes the layout into the model of `config`, puts the robot
  // at the layout's start pose at rest, refills the batteries. Throws
  // std::invalid_argument for a configuration morphology rejects.
  void reset(const SceneLayout& layout, const Configuration& config);

  // Runs control_period / physics_timestep mj_step calls with `ctrl` held
  // (kActuatorsPerModule values per module, see mjcf.hpp), accounting energy,
  // contacts and instability. Stops early when the physics becomes unstable.
  PhysicsStepInfo step_control(const double* ctrl);

  // Sheds modules: switches to the cached model of `part`, which must be a
  // sub-configuration of configuration() (validate_sub_configuration; throws
  // std::invalid_argument naming the fault otherwise), and copies time, the kept
  // modules' qpos, qvel, ctrl and warm start exactly.
  void reconfigure(const Configuration& part);

  // ---- sensors (scene geoms only: the robot never occludes itself) ----
  // Depth image from module 1's camera, row-major depth_height x depth_width,
  // planar depth / depth_max_range clipped to [0.01, 1] (1 = nothing in range).
  void render_depth(float* out) const;
  // Rows of the depth image (from the top) whose centre ray looks above the
  // horizon when the camera's carrier stands level (at least 1).
  int depth_rows_above_horizon() const;
  // The decision camera (RobotParams::decision_*) at module 1's camera position:
  // decision_depth_height x decision_depth_width, same depth encoding.
  void render_decision_depth(float* out) const;
  // The obstacle scan (RobotParams::scan_*): scan_columns distances along level
  // rays from module 1's camera position, column 0 at the left, distance /
  // depth_max_range clipped to [0.01, 1] (radial, not planar). Needs scan_columns > 0.
  void render_scan(float* out) const;
  // The same camera placed at an arbitrary pose: the camera's position (m, scene
  // frame) and the heading (yaw, rad) and pitch-up (rad) of the module carrying it.
  void render_depth_at(const double pos[3], double yaw, double pitch, float* out) const;
  // Dataset helper: the image module 1's camera would see standing level on the
  // floor at (x, y) (m) with heading yaw (rad); returns the ground-truth
  // scene_label of that position. Uses the scene of the last reset().
  int render_view_from(double x, double y, double yaw, float* out) const;
  // Left and right distance per module, normalised by distance_range, in [0, 1]:
  // out[2k] = left of module k, out[2k+1] = right (1 = nothing within range).
  void read_distances(float* out) const;
  // The world ray (origin, unit direction) of depth pixel `pixel` (row-major) at the current pose.
  void depth_ray(int pixel, double pnt[3], double dir[3]) const;
  // Nearest scene hit along a ray (m), or -1 (same geoms as the sensors).
  double cast_ray(const double pnt[3], const double dir[3], double max_dist) const;

  // ---- state ----
  int modules() const { return modules_; }
  const Configuration& configuration() const { return body_->configuration; }
  const mjModel* model() const { return model_; }
  const mjData* data() const { return data_; }
  mjData* mutable_data() { return data_; }  // for tests and tools; not for the env hot path
  const SceneLayout& layout() const { return layout_; }
  double time() const { return data_->time; }
  // Module k (0-based): body position (m) and rotation matrix (row-major 3x3).
  const double* module_pos(int k) const { return data_->xpos + 3 * module_body_[k]; }
  const double* module_mat(int k) const { return data_->xmat + 9 * module_body_[k]; }
  double module_up_z(int k) const { return module_mat(k)[8]; }  // world z of the module's z axis
  double heading() const;                                       // module 1 yaw, rad
  const double* module_energy() const { return energy_.data(); }  // J drawn per module this episode
  double energy_used() const;                                     // J, all modules (shed ones included)
  double battery_fraction(int k) const;                           // remaining, 0..1
  int substeps() const { return substeps_; }
  int compilations() const { return cache_->compilations(); }

 private:
  struct Body {  // one per configuration, made on first use
    Configuration configuration;
    int modules = 0;
    ModelPtr model;
    DataPtr data;
    std::array<int, kMaxModules> module_body{};
    bool layout_applied = false;  // the scene of the last reset() is written into `model`
  };
  Body& body(const Configuration& config);
  void bind(const Configuration& config);
  double ray_scene(const double pnt[3], const double dir[3], double max_dist) const;
  // Pinhole ray grid of one camera, in the camera-carrier frame (x forward, y left, z up).
  struct RaySet {
    std::vector<double> dirs;         // unit directions, 3 per pixel, row 0 at the top
    std::vector<double> forward_dot;  // dir . optical axis, for planar depth
  };
  static RaySet make_rays(int width, int height, double fov_x, double fov_y, double pitch);
  static RaySet make_fan(int columns, double fov_x);  // level rays, uniform in angle, radial range
  void cast_depth(const RaySet& rays, const double pos[3], const double R[9], float* out) const;
  void camera_pos(double pos[3]) const;

  RobotParams robot_;
  SceneParams scene_;
  std::shared_ptr<ModelCache> cache_;
  std::vector<std::unique_ptr<Body>> bodies_;
  Body* body_ = nullptr;  // the current configuration's
  SceneLayout layout_;
  int modules_ = 0;
  mjModel* model_ = nullptr;
  mjData* data_ = nullptr;
  std::array<int, kMaxModules> module_body_{};
  int substeps_ = 16;
  int first_obstacle_geom_ = -1, first_step_geom_ = -1, target_geom_ = -1, floor_geom_ = -1;
  std::array<double, kMaxModules> energy_{};
  double shed_energy_ = 0;  // J drawn by modules that were shed
  RaySet rays_;           // the motion camera (depth_*)
  RaySet decision_rays_;  // the decision camera (decision_*)
  RaySet scan_rays_;      // the obstacle scan (scan_*), empty when scan_columns = 0
};

}  // namespace comorph::sim
