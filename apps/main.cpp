// comorph: co-optimization of morphology and behaviour of a modular robot.
#include <spdlog/spdlog.h>

#include <exception>
#include <iostream>

#include "command_registry.hpp"

int main(int argc, char** argv) {
  CLI::App app{"comorph: co-optimize the configuration and the motion of a chain-type "
               "modular robot with hierarchical deep RL"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "comorph 0.1.0");
  for (const auto& setup : comorph::cli::command_setups()) setup(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "comorph: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
