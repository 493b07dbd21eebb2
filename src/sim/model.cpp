#include "sim/model.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstring>
#include <mutex>
#include <stdexcept>

#include "sim/mjcf.hpp"

namespace comorph::sim {

ModelPtr compile_mjcf(const std::string& xml) {
  auto vfs = std::make_unique<mjVFS>();  // ~2 MB: heap, not stack
  mj_defaultVFS(vfs.get());
  const char* name = "comorph.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), name, int(xml.size())) != 0)
    throw std::runtime_error("MuJoCo VFS: cannot allocate the model file");
  const int index = mj_findFileVFS(vfs.get(), name);
  std::memcpy(vfs->filedata[index], xml.data(), xml.size());
  char error[1000] = "";
  // MuJoCo's XML loader keeps the last parsed model in a global (mj_freeLastXML):
  // one compilation at a time when several simulation threads reset their envs.
  static std::mutex loader;
  mjModel* m = nullptr;
  {
    std::lock_guard<std::mutex> lock(loader);
    m = mj_loadXML(name, vfs.get(), error, sizeof(error));
  }
  mj_deleteVFS(vfs.get());
  if (!m) throw std::runtime_error(std::string("MuJoCo could not compile the MJCF: ") + error);
  return ModelPtr(m);
}

namespace {

void set_box(mjModel* m, int g, const Box& b) {
  m->geom_pos[3 * g + 0] = b.x;
  m->geom_pos[3 * g + 1] = b.y;
  m->geom_pos[3 * g + 2] = b.z;
  m->geom_size[3 * g + 0] = b.hx;
  m->geom_size[3 * g + 1] = b.hy;
  m->geom_size[3 * g + 2] = b.hz;
  m->geom_rbound[g] = std::sqrt(b.hx * b.hx + b.hy * b.hy + b.hz * b.hz);
}

int geom_id(const mjModel* m, const std::string& name) {
  const int id = mj_name2id(m, mjOBJ_GEOM, name.c_str());
  if (id < 0) throw std::runtime_error("model has no geom '" + name + "'");
  return id;
}

}  // namespace

void apply_layout(mjModel* m, const SceneParams& sp, const SceneLayout& s) {
  for (std::size_t k = 0; k < s.steps.size(); ++k) set_box(m, geom_id(m, "step" + std::to_string(k + 1)), s.steps[k]);
  if (int(s.obstacles.size()) > sp.max_obstacles) throw std::invalid_argument("too many obstacles for the model");
  for (int k = 0; k < sp.max_obstacles; ++k) {
    const int g = geom_id(m, "obstacle" + std::to_string(k));
    if (k < int(s.obstacles.size())) {
      set_box(m, g, s.obstacles[k]);
      m->geom_contype[g] = 1;
      m->geom_conaffinity[g] = 2;
      m->geom_group[g] = 0;
    } else {
      const double hs = 0.5 * sp.obstacle_size;
      set_box(m, g, Box{-100.0 - k, 0, -10, hs, hs, 0.5 * sp.obstacle_height});
      m->geom_contype[g] = 0;
      m->geom_conaffinity[g] = 0;
      m->geom_group[g] = 5;
    }
  }
  const int target = geom_id(m, "target");
  m->geom_pos[3 * target + 0] = s.target_x;
  m->geom_pos[3 * target + 1] = s.target_y;
  m->geom_pos[3 * target + 2] = s.platform_z + 0.2;
  const int zone = geom_id(m, "target_zone");
  m->geom_pos[3 * zone + 0] = s.target_x;
  m->geom_pos[3 * zone + 1] = s.target_y;
  m->geom_pos[3 * zone + 2] = s.platform_z + 0.002;
}

ModelCache::ModelCache(const RobotParams& robot, const SceneParams& scene)
    : robot_(robot), scene_(scene) {}

const mjModel* ModelCache::get(const Configuration& config) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const Entry& e : models_)
    if (e.config == config) return e.model.get();
  // Compiled with a neutral scene (seed 0, no obstacles); apply_layout sets the episode's.
  const SceneLayout neutral = generate_scene(scene_, 0, scene_.stair_height_a, 0);
  models_.push_back({config, compile_mjcf(build_mjcf(config, robot_, scene_, neutral))});
  ++compilations_;
  return models_.back().model.get();
}

std::string model_fault(const mjModel* m, const Configuration& config) {
  if (std::string fault = validate(config); !fault.empty()) return "invalid configuration: " + fault;
  const int n = module_count(config);
  if (m->nu != kActuatorsPerModule * n)
    return fmt::format("{} actuators for {} modules (expected {} per module)", m->nu, n, kActuatorsPerModule);
  for (int module = 1; module <= n; ++module) {
    const int body = mj_name2id(m, mjOBJ_BODY, ("module" + std::to_string(module)).c_str());
    if (body < 0) return fmt::format("module {} has no body", module);
    const int docked = module_at_face(config, module, kBackFace);
    if (!docked) continue;
    // The docked module hangs from this module's back-plate link.
    const int link = mj_name2id(m, mjOBJ_BODY, ("link" + std::to_string(module)).c_str());
    const int child = mj_name2id(m, mjOBJ_BODY, ("module" + std::to_string(docked)).c_str());
    if (link < 0 || m->body_parentid[link] != body || child < 0 || m->body_parentid[child] != link)
      return fmt::format("module {} does not hang from module {}'s back plate", docked, module);
  }
  return {};
}

namespace {
void quiet_warning(const char*) {}
}  // namespace

void install_quiet_mujoco_warnings() { mju_user_warning = quiet_warning; }

}  // namespace comorph::sim
