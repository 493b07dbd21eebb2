#include "common/file_io.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace comorph {
namespace {

[[noreturn]] void fail_write(const std::string& path, int err) {
  throw std::runtime_error(system_error_message("cannot write", path, err));
}

// Writes all of `text` to `fd` (write() may write less than asked).
void write_all(int fd, const std::string& text, const std::string& path) {
  const char* p = text.data();
  std::size_t left = text.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd);
      fail_write(path, err);
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
}

// fsync (regular files only: devices and pipes refuse it) and close, checked:
// some file systems report a full disk only here.
void sync_and_close(int fd, const std::string& path, bool regular) {
  if (regular && ::fsync(fd) != 0) {
    const int err = errno;
    ::close(fd);
    fail_write(path, err);
  }
  if (::close(fd) != 0) fail_write(path, errno);
}

bool is_special_file(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode);
}

}  // namespace

std::string system_error_message(const std::string& what, const std::string& path, int err) {
  return what + " " + path + ": " + std::strerror(err);
}

void write_file_atomic(const std::string& path, const std::string& text) {
  if (is_special_file(path)) {
    if (std::filesystem::is_directory(path)) fail_write(path, EISDIR);
    const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) fail_write(path, errno);
    write_all(fd, text, path);
    sync_and_close(fd, path, false);
    return;
  }
  // The temporary name carries the pid: two processes never share one.
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) fail_write(path, errno);
  try {
    write_all(fd, text, path);
    sync_and_close(fd, path, true);
  } catch (...) {
    ::unlink(tmp.c_str());  // frees the space the partial file took
    throw;
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    fail_write(path, err);
  }
}

void append_file(const std::string& path, const std::string& text) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0) fail_write(path, errno);
  write_all(fd, text, path);
  sync_and_close(fd, path, !is_special_file(path));
}

void flush_stdout() {
  errno = 0;
  const bool failed = std::fflush(stdout) != 0 || std::ferror(stdout);
  if (failed) {
    // errno belongs to the failed write; 0 if an earlier write failed and
    // the final flush had nothing left to write.
    const int err = errno != 0 ? errno : EIO;
    throw std::runtime_error(system_error_message("cannot write", "standard output", err));
  }
}

std::string read_text_file(const std::string& path, std::size_t max_bytes) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (!fs::exists(st)) throw std::runtime_error(path + ": no such file");
  if (fs::is_directory(st)) throw std::runtime_error(path + ": is a directory, expected a file");
  if (fs::is_regular_file(st)) {
    const auto size = fs::file_size(path, ec);
    if (!ec && size > max_bytes)
      throw std::runtime_error(path + ": " + std::to_string(size) + " bytes, more than the " +
                               std::to_string(max_bytes) + "-byte limit of this kind of file");
  }
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw std::runtime_error(system_error_message("cannot read", path, errno));
  std::string text;
  char buffer[65536];
  while (true) {
    const std::size_t n = std::fread(buffer, 1, sizeof(buffer), f);
    text.append(buffer, n);
    // Also for pipes and devices, whose size is unknown beforehand.
    if (text.size() > max_bytes) {
      std::fclose(f);
      throw std::runtime_error(path + ": more than the " + std::to_string(max_bytes) +
                               "-byte limit of this kind of file");
    }
    if (n < sizeof(buffer)) break;
  }
  const bool error = std::ferror(f);
  const int err = errno;
  std::fclose(f);
  if (error) throw std::runtime_error(system_error_message("cannot read", path, err));
  return text;
}

std::string quote_value(const std::string& value, std::size_t max_chars) {
  if (value.size() <= max_chars) return value;
  return value.substr(0, max_chars) + "... (" + std::to_string(value.size()) + " characters)";
}

}  // namespace comorph
