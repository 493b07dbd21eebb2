// The --scenario options: a name in task's scenario registry; any other is
// refused while the command line is parsed, with the registry's names.
#pragma once

#include <CLI/CLI.hpp>

#include <exception>
#include <string>

#include "task/scenario.hpp"

namespace comorph::cli {

inline CLI::Validator scenario_name() {
  return CLI::Validator(
      [](std::string& input) -> std::string {
        try {
          task::scenario_named(input);
          return "";
        } catch (const std::exception& e) {
          return e.what();
        }
      },
      "SCENARIO");
}

inline CLI::Option* add_scenario_option(CLI::App* app, std::string& scenario) {
  return app->add_option("--scenario", scenario, enum_name_list<task::Scenario>())->check(scenario_name());
}

}  // namespace comorph::cli
