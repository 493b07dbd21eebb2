// gzip (RFC 1952) in memory, through zlib: the training log of an exported
// run (results/*/episodes.csv.gz) is a fifth of its text, which keeps a run
// with 256 x 256 networks under results/' 2 MB.
#pragma once

#include <cstddef>
#include <string>

namespace comorph {

// `text` as one gzip member (best compression).
std::string gzip_compress(const std::string& text);

// The text of gzip `data` read from `source` (named in errors); throws
// "<source>: not gzip data" / "<source>: damaged gzip data (...)" /
// "<source>: more than the N-byte limit once decompressed".
std::string gzip_decompress(const std::string& data, const std::string& source, std::size_t max_bytes);

// True when `path` names a gzip file by its suffix (".gz").
bool has_gzip_suffix(const std::string& path);

}  // namespace comorph
