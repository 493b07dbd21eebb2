#include "report/process.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

extern char** environ;

namespace comorph::report {
namespace {

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A private temporary file for a child's output, removed by the caller.
std::string make_temp_log() {
  const char* dir = std::getenv("TMPDIR");
  std::string templ = std::string(dir && *dir ? dir : "/tmp") + "/comorph-tool-XXXXXX";
  std::vector<char> buf(templ.begin(), templ.end());
  buf.push_back('\0');
  const int fd = mkstemp(buf.data());
  if (fd < 0) throw std::runtime_error(fmt::format("cannot create a temporary file: {}", std::strerror(errno)));
  close(fd);
  return std::string(buf.data());
}

std::vector<char*> c_argv(const std::vector<std::string>& argv) {
  std::vector<char*> out;
  for (const auto& a : argv) out.push_back(const_cast<char*>(a.c_str()));
  out.push_back(nullptr);
  return out;
}

std::string describe_status(int status) {
  if (WIFEXITED(status)) return fmt::format("exit status {}", WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return fmt::format("signal {}", WTERMSIG(status));
  return "unknown status";
}

// Spawns argv with stdin from `stdin_fd` (or /dev/null when -1) and stdout and
// stderr to `log_path`.
pid_t spawn(const std::vector<std::string>& argv, int stdin_fd, const std::string& log_path,
            int close_in_child) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (stdin_fd >= 0) {
    posix_spawn_file_actions_adddup2(&actions, stdin_fd, 0);
  } else {
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  }
  if (close_in_child >= 0) posix_spawn_file_actions_addclose(&actions, close_in_child);
  posix_spawn_file_actions_addopen(&actions, 1, log_path.c_str(), O_WRONLY | O_TRUNC, 0600);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  pid_t pid = -1;
  auto args = c_argv(argv);
  const int rc = posix_spawnp(&pid, argv[0].c_str(), &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw std::runtime_error(fmt::format("cannot start {}: {}", argv[0], std::strerror(rc)));
  return pid;
}

int wait_for(pid_t pid) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) throw std::runtime_error(fmt::format("waitpid: {}", std::strerror(errno)));
  }
  return status;
}

}  // namespace

std::string find_executable(const std::string& name) {
  if (name.find('/') != std::string::npos) return access(name.c_str(), X_OK) == 0 ? name : "";
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "/usr/bin:/bin");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (dir.empty()) continue;
    const std::string candidate = dir + "/" + name;
    struct stat st {};
    if (stat(candidate.c_str(), &st) == 0 && S_ISREG(st.st_mode) && access(candidate.c_str(), X_OK) == 0)
      return candidate;
  }
  return "";
}

std::string require_executable(const std::string& name, const std::string& debian_package) {
  std::string path = find_executable(name);
  if (path.empty())
    throw std::runtime_error(fmt::format(
        "'{}' is not installed (not found on PATH); install the Debian package {} "
        "(scripts/install-deps.sh does)", name, debian_package));
  return path;
}

std::string run_tool(const std::vector<std::string>& argv) {
  const std::string log = make_temp_log();
  const pid_t pid = spawn(argv, -1, log, -1);
  const int status = wait_for(pid);
  std::string output = read_file(log);
  std::remove(log.c_str());
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw std::runtime_error(fmt::format("{} failed ({}): {}", argv[0], describe_status(status), output));
  return output;
}

ChildInput::ChildInput(const std::vector<std::string>& argv) : tool_(argv.at(0)) {
  log_path_ = make_temp_log();
  int sv[2];
  if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0)
    throw std::runtime_error(fmt::format("socketpair: {}", std::strerror(errno)));
  // The child reads sv[1] as stdin (dup2 clears CLOEXEC on fd 0); we keep sv[0].
  try {
    pid_ = spawn(argv, sv[1], log_path_, -1);
  } catch (...) {
    close(sv[0]);
    close(sv[1]);
    std::remove(log_path_.c_str());
    throw;
  }
  close(sv[1]);
  shutdown(sv[0], SHUT_RD);
  fd_ = sv[0];
}

ChildInput::~ChildInput() {
  if (pid_ > 0) {
    int status = 0;
    close_and_wait(&status);
  }
  std::remove(log_path_.c_str());
}

std::string ChildInput::close_and_wait(int* status) {
  if (fd_ >= 0) close(fd_);
  fd_ = -1;
  *status = pid_ > 0 ? wait_for(pid_) : 0;
  pid_ = -1;
  return read_file(log_path_);
}

void ChildInput::write(const void* data, size_t bytes) {
  const char* p = static_cast<const char*>(data);
  while (bytes > 0) {
    const ssize_t n = send(fd_, p, bytes, MSG_NOSIGNAL);
    if (n < 0) {
      if (errno == EINTR) continue;
      const std::string err = std::strerror(errno);
      int status = 0;
      const std::string log = close_and_wait(&status);
      throw std::runtime_error(fmt::format("{} stopped reading its input ({}; {}): {}", tool_, err,
                                           describe_status(status), log));
    }
    p += n;
    bytes -= static_cast<size_t>(n);
  }
}

void ChildInput::finish() {
  int status = 0;
  const std::string log = close_and_wait(&status);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw std::runtime_error(fmt::format("{} failed ({}): {}", tool_, describe_status(status), log));
}

}  // namespace comorph::report
