#include "common/checksum.hpp"

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "common/file_io.hpp"

namespace comorph {

std::string file_checksum(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw std::runtime_error(system_error_message("cannot read", path, errno));
  std::uint64_t h = 14695981039346656037ULL;  // FNV-1a 64 offset basis
  unsigned char buffer[1 << 16];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof(buffer), f)) > 0)
    for (std::size_t i = 0; i < n; ++i) h = (h ^ buffer[i]) * 1099511628211ULL;  // FNV prime
  const bool error = std::ferror(f);
  const int err = errno;
  std::fclose(f);
  if (error) throw std::runtime_error(system_error_message("cannot read", path, err));
  char hex[17];
  std::snprintf(hex, sizeof(hex), "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

void write_checksums(const std::string& dir, const std::vector<std::string>& names) {
  write_checksums(dir, names, {});
}

void write_checksums(const std::string& dir, const std::vector<std::string>& names,
                     const std::map<std::string, std::string>& known) {
  namespace fs = std::filesystem;
  std::string text;
  for (const auto& name : names) {
    const auto sum = known.find(name);
    text += (sum != known.end() ? sum->second : file_checksum((fs::path(dir) / name).string())) + "  " + name + "\n";
  }
  write_file_atomic((fs::path(dir) / kChecksumFile).string(), text);
}

std::string verify_checksums(const std::string& dir) {
  namespace fs = std::filesystem;
  const fs::path list = fs::path(dir) / kChecksumFile;
  if (!fs::exists(list)) return list.string() + ": missing (the checkpoint is incomplete)";
  std::istringstream in(read_text_file(list.string()));
  std::string line;
  int files = 0;
  while (std::getline(in, line)) {
    const auto gap = line.find("  ");
    if (line.size() < 19 || gap != 16) return list.string() + ": malformed line '" + quote_value(line) + "'";
    const std::string sum = line.substr(0, 16), name = line.substr(18);
    const std::string path = (fs::path(dir) / name).string();
    if (!fs::is_regular_file(path)) return path + ": missing (listed in " + list.string() + ")";
    const std::string actual = file_checksum(path);
    if (actual != sum)
      return path + ": checksum mismatch (" + actual + ", " + list.string() + " says " + sum +
             "): the file is corrupted";
    ++files;
  }
  if (files == 0) return list.string() + ": lists no files";
  return "";
}

}  // namespace comorph
