#include "task/env_config.hpp"

#include <filesystem>
#include <stdexcept>

#include "common/yaml_fields.hpp"

namespace comorph::task {

TaskParams task_params_from_yaml(const std::string& text, const std::string& source, TaskParams p) {
  YamlFields f(source);
  f.add("r1.tau1", &p.r1.tau1, -1e4, 1e4);
  f.add("r1.tau2", &p.r1.tau2, -1e4, 1e4);
  f.add("r1.tau3", &p.r1.tau3, -1e4, 1e4);
  f.add("r1.r_u", &p.r1.r_u, -1e4, 0);
  f.add("r1.r_g", &p.r1.r_g, 0, 1e5);
  f.add("r1.alpha_g", &p.r1.alpha_g, 0, 100);
  f.add("r1.t_sum", &p.r1.t_sum, 1, 1e7);
  f.add("r2.sigma1", &p.r2.sigma1, 0, 100);
  f.add("r2.s_base", &p.r2.s_base, 1e-3, 1);
  f.add("r2.r_s", &p.r2.r_s, 0, 1e5);
  f.add("r2.sigma3", &p.r2.sigma3, 0, 10);
  f.add("objective.w_t", &p.objective.w_t, 0, 100);
  f.add("objective.w_e", &p.objective.w_e, 0, 100);
  f.add("objective.w_d", &p.objective.w_d, 0, 100);
  f.add("objective.t_max_s", &p.objective.t_max_s, 1e-3, 1e6);
  f.add("objective.energy_scale_J", &p.objective.energy_scale_J, 1e-3, 1e9);
  f.add("max_steps", &p.max_steps, 1, 10000000);
  f.add("overturn_up_z", &p.overturn_up_z, -1, 1);
  f.add("start_zone_length", &p.start_zone_length, 0, 100);
  f.add("stair_goal_offset", &p.stair_goal_offset, 0, 10);
  f.apply_text(text);
  return p;
}

namespace {
const char* const kEnvFiles[] = {"robot.yaml", "scene.yaml", "motion.yaml", "task.yaml"};

void require_directory(const std::string& dir) {
  namespace fs = std::filesystem;
  if (!fs::exists(dir)) throw std::runtime_error(dir + ": no such config directory (robot/scene/motion/task.yaml)");
  if (!fs::is_directory(dir)) throw std::runtime_error(dir + ": not a directory (expected robot/scene/motion/task.yaml)");
}
}  // namespace

std::string env_files_text(const std::string& dir) {
  namespace fs = std::filesystem;
  require_directory(dir);
  std::string text;
  for (const char* name : kEnvFiles) {
    const std::string path = (fs::path(dir) / name).string();
    if (!fs::exists(path)) {
      text += std::string("# ") + name + ": absent (built-in defaults)\n";
      continue;
    }
    YAML::Emitter e;
    e << load_yaml_file(path);
    text += std::string("# ") + name + "\n" + e.c_str() + "\n";
  }
  return text;
}

EnvConfig load_env_config(const std::string& dir) {
  namespace fs = std::filesystem;
  require_directory(dir);
  EnvConfig c;
  auto path = [&](const char* name) { return (fs::path(dir) / name).string(); };
  if (fs::exists(path("robot.yaml"))) c.robot = sim::load_robot_params(path("robot.yaml"));
  if (fs::exists(path("scene.yaml"))) c.scene = sim::load_scene_params(path("scene.yaml"));
  if (fs::exists(path("motion.yaml")))
    c.motion = control::motion_params_from_yaml(read_text_file(path("motion.yaml")), path("motion.yaml"));
  if (fs::exists(path("task.yaml")))
    c.task = task_params_from_yaml(read_text_file(path("task.yaml")), path("task.yaml"));
  return c;
}

}  // namespace comorph::task
