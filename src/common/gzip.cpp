#include "common/gzip.hpp"

#include <zlib.h>

#include <stdexcept>

namespace comorph {
namespace {

constexpr int kGzipWindowBits = 15 + 16;  // zlib: 32 KiB window, gzip header and trailer

std::string zlib_reason(const z_stream& z, int code) {
  return z.msg ? std::string(z.msg) : "zlib error " + std::to_string(code);
}

}  // namespace

std::string gzip_compress(const std::string& text) {
  z_stream z{};
  if (deflateInit2(&z, Z_BEST_COMPRESSION, Z_DEFLATED, kGzipWindowBits, 8, Z_DEFAULT_STRATEGY) != Z_OK)
    throw std::runtime_error("gzip: cannot start the compressor");
  std::string out(deflateBound(&z, static_cast<uLong>(text.size())), '\0');
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(text.data()));
  z.avail_in = static_cast<uInt>(text.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  const int code = deflate(&z, Z_FINISH);  // deflateBound guarantees one call suffices
  const std::string reason = code == Z_STREAM_END ? "" : zlib_reason(z, code);
  out.resize(z.total_out);
  deflateEnd(&z);
  if (!reason.empty()) throw std::runtime_error("gzip: " + reason);
  return out;
}

std::string gzip_decompress(const std::string& data, const std::string& source, std::size_t max_bytes) {
  if (data.size() < 2 || static_cast<unsigned char>(data[0]) != 0x1f || static_cast<unsigned char>(data[1]) != 0x8b)
    throw std::runtime_error(source + ": not gzip data");
  z_stream z{};
  if (inflateInit2(&z, kGzipWindowBits) != Z_OK) throw std::runtime_error(source + ": cannot start the decompressor");
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
  z.avail_in = static_cast<uInt>(data.size());
  std::string out;
  char buffer[65536];
  int code = Z_OK;
  while (code != Z_STREAM_END) {
    z.next_out = reinterpret_cast<Bytef*>(buffer);
    z.avail_out = sizeof(buffer);
    code = inflate(&z, Z_NO_FLUSH);
    if (code != Z_OK && code != Z_STREAM_END) {
      // Z_BUF_ERROR with input left over cannot happen; without input it is a cut file.
      const std::string reason = code == Z_BUF_ERROR ? "the file ends early" : zlib_reason(z, code);
      inflateEnd(&z);
      throw std::runtime_error(source + ": damaged gzip data (" + reason + ")");
    }
    out.append(buffer, sizeof(buffer) - z.avail_out);
    if (out.size() > max_bytes) {
      inflateEnd(&z);
      throw std::runtime_error(source + ": more than the " + std::to_string(max_bytes) +
                               "-byte limit once decompressed");
    }
  }
  inflateEnd(&z);
  return out;
}

bool has_gzip_suffix(const std::string& path) { return path.size() > 3 && path.compare(path.size() - 3, 3, ".gz") == 0; }

}  // namespace comorph
