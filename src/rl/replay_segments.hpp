// A replay buffer in training checkpoints as immutable segment files plus a
// small index, so that a checkpoint writes only the transitions added since
// the one before instead of the whole buffer (up to 300 k transitions, 170 MB).
//
// A segment holds the transitions [first, first + count) by global index
// (ReplayBuffer::added()) and is never changed once written. Each checkpoint
// directory holds every segment it needs: those of the previous checkpoint
// that still hold transitions of the buffer, as hard links (the bytes are not
// written again; a copy where the file system has no hard links), plus one
// new segment. Removing a checkpoint directory therefore never breaks
// another one, and the directory swap of the trainer (checkpoint.tmp ->
// checkpoint -> checkpoint.old) works as for any other file. The index
// <name>-replay.yaml lists the segments with their checksums (FNV-1a 64, as
// checksums.txt; they let the next checkpoint list a linked file without
// reading it again).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "rl/replay_buffer.hpp"

namespace comorph::rl {

struct ReplaySegment {
  std::string file;        // name inside the checkpoint directory
  std::int64_t first = 0;  // global index of its first transition
  std::int64_t count = 0;  // transitions in it
  std::string checksum;    // FNV-1a 64 of the file (common/checksum.hpp)
};

// A buffer's segments as the last checkpoint written or read holds them.
struct ReplaySegments {
  std::string directory;   // the checkpoint directory that holds the files; empty: none
  std::int64_t capacity = 0;
  std::int64_t added = 0;  // ReplayBuffer::added() when they were written
  std::vector<ReplaySegment> segments;
};

// "<name>-replay.yaml"
std::string replay_index_name(const std::string& name);

// Writes `buffer` as `name` ("motion", "config_model") into `dir`, a
// checkpoint directory being built: the segments of `previous` that still hold
// transitions of the buffer are linked from previous.directory, the
// transitions added since previous.added go to one new segment, and the index
// last. Appends every file it put in `dir` to `files` and the sums it knows to
// `sums` (for write_checksums). Returns the new state, with directory = dir
// (the caller sets the final name after renaming dir).
ReplaySegments write_replay_segments(const ReplayBuffer& buffer, const std::string& name, const std::string& dir,
                                     const ReplaySegments& previous, std::vector<std::string>& files,
                                     std::map<std::string, std::string>& sums);

// Reads dir/<name>-replay.yaml and its segments into `buffer` and returns
// their state. Throws naming the file when the index is missing, does not fit
// the buffer or does not cover every transition it counts.
ReplaySegments read_replay_segments(ReplayBuffer& buffer, const std::string& name, const std::string& dir);

}  // namespace comorph::rl
