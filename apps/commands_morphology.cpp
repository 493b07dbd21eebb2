// `comorph config ...`: write and check robot configuration files; list the
// settings of a run's config file.
#include <fmt/format.h>

#include <iostream>
#include <stdexcept>

#include "command_registry.hpp"
#include "common/resources.hpp"
#include "coopt/config_reference.hpp"
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
  auto* config = app.add_subcommand(
      "config", "write or check robot configuration files (C_a, C_s); list the settings of a run's config");
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

  auto* keys = config->add_subcommand(
      "keys", "list every setting of a run's config file: key, default, type and range, meaning (docs/config.md)");
  static std::string preset;
  static bool markdown = false;
  keys->add_option("--preset", preset, "also show this preset's values, '*' where they differ from the default");
  keys->add_flag("--markdown", markdown, "print docs/config.md (the same list as Markdown)");
  keys->callback([] {
    if (markdown && !preset.empty()) throw CLI::ValidationError("--markdown", "lists the defaults; drop --preset");
    if (markdown) {
      std::cout << coopt::config_reference_markdown();
    } else if (preset.empty()) {
      std::cout << coopt::config_keys_text();
    } else {
      const coopt::CooptConfig c = coopt::load_coopt_config(preset);
      std::cout << coopt::config_keys_text(&c);
    }
  });
}};

}  // namespace
