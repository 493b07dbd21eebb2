#include "common/resources.hpp"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>

namespace comorph {
namespace {

namespace fs = std::filesystem;

constexpr const char* kMarker = "configs/sim/robot.yaml";  // a file every resource tree has

bool holds_resources(const fs::path& dir) {
  std::error_code ec;
  return fs::is_regular_file(dir / kMarker, ec);
}

// `start` or its first parent that holds the resources; empty if none does.
fs::path search_upwards(fs::path start) {
  std::error_code ec;
  start = fs::weakly_canonical(start, ec);
  for (fs::path dir = start; !dir.empty(); dir = dir.parent_path()) {
    if (holds_resources(dir)) return dir;
    if (dir == dir.parent_path()) break;
  }
  return {};
}

// The file this code was loaded from: the executable, or the shared library
// (the Python module) it is linked into.
fs::path own_binary() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&own_binary), &info) != 0 && info.dli_fname != nullptr &&
      info.dli_fname[0] != '\0')
    return fs::path(info.dli_fname);
  std::error_code ec;
  return fs::read_symlink("/proc/self/exe", ec);
}

std::string find_resource_dir() {
  if (const char* env = std::getenv("COMORPH_RESOURCES"); env != nullptr && env[0] != '\0') {
    if (!holds_resources(env))
      throw std::runtime_error(std::string("COMORPH_RESOURCES=") + env + " does not hold " + kMarker);
    return fs::weakly_canonical(env).string();
  }
  const fs::path binary = own_binary();
  if (fs::path dir = search_upwards(binary.parent_path()); !dir.empty()) return dir.string();
  std::error_code ec;
  const fs::path cwd = fs::current_path(ec);
  if (fs::path dir = search_upwards(cwd); !dir.empty()) return dir.string();
  throw std::runtime_error(std::string("comorph's data files (") + kMarker + ") are in no parent of " +
                           binary.string() + " nor of the current directory " + cwd.string() +
                           "; set COMORPH_RESOURCES to the directory that holds configs/");
}

}  // namespace

const std::string& resource_dir() {
  static const std::string dir = find_resource_dir();
  return dir;
}

std::string resource_path(const std::string& relative) { return resource_dir() + "/" + relative; }

std::string given_or_resource(const std::string& given, const std::string& relative) {
  return given.empty() ? resource_path(relative) : given;
}

}  // namespace comorph
