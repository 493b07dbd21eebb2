// Checked file input and output, shared by every layer and the CLI.
//
// Writes: every byte is written, flushed (fsync) and closed before a write
// counts as done, and a failure throws std::runtime_error
// "cannot write <path>: <the system's reason>" (e.g. "No space left on
// device"). Whole files go to a temporary name beside the target and are
// renamed over it, so a reader never sees a file that looks complete but is
// not. A target that exists and is not a regular file (/dev/full, /dev/null,
// a pipe) is written in place: there is nothing to rename over.
//
// Reads: input files are refused above a size cap before anything is parsed
// (a 50 MB YAML would need gigabytes in yaml-cpp), and a directory given
// where a file is meant is an error, not an empty file.
#pragma once

#include <cstddef>
#include <string>

namespace comorph {

// Largest configuration file (YAML) comorph reads: real ones are a few KiB.
inline constexpr std::size_t kMaxConfigFileBytes = 1 << 20;  // 1 MiB

// "<what> <path>: <strerror(err)>", e.g. "cannot write runs/a/x.json: No space left on device".
std::string system_error_message(const std::string& what, const std::string& path, int err);

// Writes `text` as the whole file `path` (temporary file + rename).
void write_file_atomic(const std::string& path, const std::string& text);
// Appends `text` to `path` (created if missing); written and closed, or throws.
void append_file(const std::string& path, const std::string& text);
// Flushes standard output; throws "cannot write standard output: <reason>"
// when any write to it failed (`comorph export-mjcf > /dev/full`).
void flush_stdout();

// The whole of a regular file of at most `max_bytes`; throws naming the file
// when it is missing, a directory, too large or unreadable.
std::string read_text_file(const std::string& path, std::size_t max_bytes = kMaxConfigFileBytes);

// At most `max_chars` of a value for an error message ("abc... (50000000 characters)").
std::string quote_value(const std::string& value, std::size_t max_chars = 80);

}  // namespace comorph
