// `comorph config ...`: write and check configuration files.
#include <fmt/format.h>

#include <iostream>
#include <stdexcept>

#include "command_registry.hpp"
#include "common/resources.hpp"
#include "morphology/configuration.hpp"
#include "sim/mjcf.hpp"
#include "sim/model.hpp"
#include "task/env_config.hpp"

namespace {

using namespace comorph;

// Loads the file (morphology names the first fault), then builds and compiles
// the robot the simulator would run and checks it against the configuration.
void validate_file(const std::string& path, const std::string& config_dir) {
  const Configuration c = load_configuration(path);
  const task::EnvConfig env = task::load_env_config(given_or_resource(config_dir, "configs/sim"));
  const sim::SceneLayout neutral = sim::generate_scene(env.scene, 0, env.scene.stair_height_a, 0);
  const sim::ModelPtr model = sim::compile_mjcf(sim::build_mjcf(c, env.robot, env.scene, neutral));
  if (std::string fault = sim::model_fault(model.get(), c); !fault.empty())
    throw std::runtime_error(path + ": the simulator built a different robot: " + fault);
  std::cout << fmt::format("{}: valid, {}; the simulator builds it: {} joints, {} actuators\n", path, describe(c),
                           model->njnt, model->nu);
}

comorph::cli::CommandRegistration registration{[](CLI::App& app) {
  auto* config = app.add_subcommand("config", "write or check robot configuration files (C_a, C_s)");
  config->require_subcommand(1);

  auto* chain = config->add_subcommand("chain", "print the YAML of a chain of N modules");
  static int modules = 2;
  chain->add_option("--modules,-n", modules, fmt::format("number of modules ({}..{})", kMinModules, kMaxModules))
      ->required();
  chain->callback([] { std::cout << to_yaml(make_chain(modules)); });

  auto* check = config->add_subcommand(
      "validate", "check a configuration file and build its robot in the simulator; names the fault");
  static std::string path;
  static std::string config_dir;  // "": configs/sim of resource_dir()
  check->add_option("file", path, "configuration YAML")->required();
  check->add_option("--config-dir", config_dir, cli::kConfigDirHelp);
  check->callback([] { validate_file(path, config_dir); });
}};

}  // namespace
