// `comorph config ...`: write and check configuration files.
#include <iostream>
#include <stdexcept>

#include "command_registry.hpp"
#include "morphology/configuration.hpp"

namespace {

comorph::cli::CommandRegistration registration{[](CLI::App& app) {
  auto* config = app.add_subcommand("config", "write or check robot configuration files (C_a, C_s)");
  config->require_subcommand(1);

  auto* chain = config->add_subcommand("chain", "print the YAML of a chain of N modules");
  static int modules = 2;
  chain->add_option("--modules,-n", modules, "number of modules (2..10)")->required();
  chain->callback([] { std::cout << comorph::to_yaml(comorph::make_chain(modules)); });

  auto* check = config->add_subcommand("validate", "check a configuration file; names the fault");
  static std::string path;
  check->add_option("file", path, "configuration YAML")->required();
  check->callback([] {
    const comorph::Configuration c = comorph::load_configuration(path);  // throws with the fault
    std::cout << path << ": valid, " << comorph::describe(c) << "\n";
  });
}};

}  // namespace
