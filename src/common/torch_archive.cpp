#include "common/torch_archive.hpp"

#include <fcntl.h>
#include <torch/serialize/output-archive.h>
#include <unistd.h>

#include <cerrno>
#include <stdexcept>

#include "common/file_io.hpp"

namespace comorph {

void save_archive(torch::serialize::OutputArchive& archive, const std::string& path) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error(system_error_message("cannot write", path, errno));
  int error = 0;  // errno of the first failed write; later bytes are dropped
  archive.save_to([&](const void* data, std::size_t size) -> std::size_t {
    const char* p = static_cast<const char*>(data);
    std::size_t left = error ? 0 : size;
    while (left > 0) {
      const ssize_t n = ::write(fd, p, left);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) {
        error = errno;
        break;
      }
      p += n;
      left -= static_cast<std::size_t>(n);
    }
    return size;  // always "written": see the header
  });
  if (!error && ::fsync(fd) != 0) error = errno;
  if (::close(fd) != 0 && !error) error = errno;
  if (error) throw std::runtime_error(system_error_message("cannot write", path, error));
}

}  // namespace comorph
