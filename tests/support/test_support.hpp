// Helpers shared by the tests that run whole commands: a fresh temporary
// directory per test process, reading a file whole, and running the built
// `comorph` (COMORPH_EXE, set by the test's CMakeLists) with its output kept.
// Header only; a test target gets it with
// target_include_directories(<test> PRIVATE ${PROJECT_SOURCE_DIR}/tests).
#pragma once

#include <unistd.h>

#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

namespace comorph::test_support {

// <tmp>/comorph_<name>_<pid>, emptied and created.
inline std::string fresh_temp_dir(const std::string& name) {
  const std::filesystem::path p =
      std::filesystem::temp_directory_path() / ("comorph_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p.string();
}

inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The message of what `f` throws; "" when it throws nothing.
inline std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

#ifdef COMORPH_EXE
// Runs `comorph <args>` through the shell; returns its exit status (as
// std::system does), stdout and stderr together in `output`.
inline int run_comorph(const std::string& args, std::string& output) {
  const std::filesystem::path log =
      std::filesystem::temp_directory_path() / ("comorph_cli_" + std::to_string(::getpid()) + ".log");
  const int status = std::system((std::string(COMORPH_EXE) + " " + args + " > " + log.string() + " 2>&1").c_str());
  output = read_text(log);
  std::filesystem::remove(log);
  return status;
}
#endif

}  // namespace comorph::test_support
