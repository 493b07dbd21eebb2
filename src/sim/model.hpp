// Compiling MJCF and caching compiled models per configuration. The scene part
// of a cached model is a set of slots (steps, obstacles, target) that
// apply_layout() rewrites per episode, so a new seed never recompiles.
#pragma once

#include <mujoco/mujoco.h>

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "morphology/configuration.hpp"
#include "sim/params.hpp"
#include "sim/scene.hpp"

namespace comorph::sim {

struct ModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct DataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using ModelPtr = std::unique_ptr<mjModel, ModelDeleter>;
using DataPtr = std::unique_ptr<mjData, DataDeleter>;

// Compiles MJCF text (through an in-memory VFS); throws std::runtime_error with
// MuJoCo's message on failure.
ModelPtr compile_mjcf(const std::string& xml);

// Writes the layout into the scene slots of a model built by build_mjcf with
// the same SceneParams: step and obstacle boxes (pos, size, rbound), unused
// obstacle slots parked, target position. Does not touch the robot.
void apply_layout(mjModel* m, const SceneParams& scene, const SceneLayout& layout);

// Empty when the compiled model `m` is the robot `config` describes (a body
// per module, each docked module hanging from the back plate it docks to,
// kActuatorsPerModule actuators per module); otherwise names the first difference.
std::string model_fault(const mjModel* m, const Configuration& config);

// Compiled models keyed by configuration, compiled on first request and kept
// for the process (thread-safe). Each caller copies the model it mutates.
class ModelCache {
 public:
  ModelCache(const RobotParams& robot, const SceneParams& scene);
  // Compiles once per configuration; throws std::invalid_argument for one
  // morphology rejects.
  const mjModel* get(const Configuration& config);
  int compilations() const { return compilations_; }

 private:
  struct Entry {
    Configuration config;
    ModelPtr model;
  };
  RobotParams robot_;
  SceneParams scene_;
  std::mutex mutex_;
  std::vector<Entry> models_;  // a few configurations: a linear search is enough
  int compilations_ = 0;
};

// Installs a MuJoCo warning handler that counts warnings instead of printing
// (mj_step's own warning counters in mjData still work). Idempotent.
void install_quiet_mujoco_warnings();

}  // namespace comorph::sim
