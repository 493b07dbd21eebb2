// Each apps/commands_*.cpp adds its subcommands to the `comorph` app through a
// static CommandRegistration, so that areas do not edit one shared file.
// A command's callback reports failure by throwing; main() prints the message
// and exits with status 1 (status 2 is CLI11's for bad usage).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <vector>

namespace comorph::cli {

// The help of every --config-dir option: its default (common/resources.hpp)
// is looked up only when a command uses it.
inline constexpr const char* kConfigDirHelp =
    "directory of robot/scene/motion/task.yaml (default: configs/sim of comorph's data files)";

using CommandSetup = std::function<void(CLI::App& app)>;

inline std::vector<CommandSetup>& command_setups() {
  static std::vector<CommandSetup> setups;
  return setups;
}

struct CommandRegistration {
  explicit CommandRegistration(CommandSetup setup) { command_setups().push_back(std::move(setup)); }
};

}  // namespace comorph::cli
