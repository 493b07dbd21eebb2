// Where comorph's data files are (configs/sim, configs/rl, the paper's
// reference tables), found at run time rather than compiled in, so that a
// moved or copied build still finds them and says where it looked if not.
#pragma once

#include <string>

namespace comorph {

// The directory that holds configs/ (the repository, or a copy of its
// configs/ tree beside the program). In this order:
//   1. $COMORPH_RESOURCES, if set (it must hold configs/sim/robot.yaml);
//   2. the first parent of the program (the executable, or the Python
//      module's library) that holds configs/sim/robot.yaml;
//   3. the current directory, or one of its parents, if it holds it.
// Throws std::runtime_error naming the places it tried otherwise.
const std::string& resource_dir();

// resource_dir() + "/" + relative, e.g. resource_path("configs/sim").
std::string resource_path(const std::string& relative);

// `given` if not empty (a path the user gave), else resource_path(relative):
// the default of a command-line path option, looked up only when used.
std::string given_or_resource(const std::string& given, const std::string& relative);

}  // namespace comorph
