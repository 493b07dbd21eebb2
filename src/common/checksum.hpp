// Per-file checksums of a directory of files (a training checkpoint), so that
// flipped, truncated or emptied files are found before they are loaded:
// LibTorch's archive reader does not verify content.
//
// The sum is 64-bit FNV-1a: not a defence against tampering, but any change of
// a single byte changes it (each step is a bijection of the running value),
// and it needs no library.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace comorph {

// FNV-1a 64 of a file's bytes as 16 hex digits; throws naming the file when it cannot be read.
std::string file_checksum(const std::string& path);

// Name of the checksum file in a checked directory.
inline constexpr const char* kChecksumFile = "checksums.txt";

// Writes dir/checksums.txt ("<sum>  <name>" a line) for the given files of
// `dir`; call it after the files are complete (checked write + rename).
void write_checksums(const std::string& dir, const std::vector<std::string>& names);
// The same, with the sums of some files already known (name -> sum): files
// hard-linked unchanged from an earlier checkpoint are not read again.
void write_checksums(const std::string& dir, const std::vector<std::string>& names,
                     const std::map<std::string, std::string>& known);
// "" when every file listed in dir/checksums.txt has its sum; otherwise what
// is wrong, naming the file ("dir/motion.pt: checksum mismatch (...)").
// A directory without checksums.txt is incomplete.
std::string verify_checksums(const std::string& dir);

}  // namespace comorph
