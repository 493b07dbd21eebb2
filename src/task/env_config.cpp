#include "task/env_config.hpp"

#include <filesystem>
#include <stdexcept>

#include "common/yaml_fields.hpp"

namespace comorph::task {

void add_fields(YamlFields& f, TaskParams& p) {
  f.add("r1.tau1", &p.r1.tau1, -1e4, 1e4, "R1 (Eq. 6): per m of progress towards the current goal");
  f.add("r1.tau2", &p.r1.tau2, -1e4, 1e4, "R1: weight of cos(heading error)");
  f.add("r1.tau3", &p.r1.tau3, -1e4, 1e4, "R1: weight of the failure term r_u");
  f.add("r1.r_u", &p.r1.r_u, -1e4, 0, "R1: reward of a failure (collision, overturn, leaving the area, empty battery)");
  f.add("r1.r_g", &p.r1.r_g, 0, 1e5, "R1: reward on reaching the target");
  f.add("r1.alpha_g", &p.r1.alpha_g, 0, 100, "R1: early-finish bonus, tau4 = 1 + alpha_g (1 - t / t_sum)");
  f.add("r1.t_sum", &p.r1.t_sum, 1, 1e7, "R1: control steps of the early-finish bonus");
  f.add("r2.sigma1", &p.r2.sigma1, 0, 100, "R2 (Eq. 7): weight of the segment's summed R1");
  f.add("r2.s_base", &p.r2.s_base, 1e-3, 1, "R2: m, sigma2 = 1 + stair height / s_base on the stairs");
  f.add("r2.r_s", &p.r2.r_s, 0, 1e5, "R2: reward when the stairs are climbed in the segment");
  f.add("r2.sigma3", &p.r2.sigma3, 0, 10, "R2: weight per J of the energy spent on the stairs");
  f.add("r2.energy_if_climbed", &p.r2.energy_if_climbed,
        "R2: only the segment that climbed the stairs pays sigma3 x its stair energy (a failed climb pays none)");
  f.add("objective.w_t", &p.objective.w_t, 0, 100, "F(H) (Eq. 1): weight of the time T");
  f.add("objective.w_e", &p.objective.w_e, 0, 100, "F(H): weight of the energy E");
  f.add("objective.w_d", &p.objective.w_d, 0, 100, "F(H): weight of the distance fraction D");
  f.add("objective.t_max_s", &p.objective.t_max_s, 1e-3, 1e6, "F(H): s, T = time / t_max_s");
  f.add("objective.energy_scale_J", &p.objective.energy_scale_J, 1e-3, 1e9, "F(H): J, E = energy / energy_scale_J");
  f.add("max_steps", &p.max_steps, 1, 10000000, "control steps before an episode is cut (truncated)");
  f.add("overturn_up_z", &p.overturn_up_z, -1, 1, "a module whose up axis has a world z below this is overturned");
  f.add("start_zone_length", &p.start_zone_length, 0, 100,
        "m behind the start face the robot may back up before leaving the area");
  f.add("stair_goal_offset", &p.stair_goal_offset, 0, 10,
        "m, the goal while the stairs are not climbed = top edge + this + chain length");
}

TaskParams task_params_from_yaml(const std::string& text, const std::string& source, TaskParams p) {
  YamlFields f(source);
  add_fields(f, p);
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
