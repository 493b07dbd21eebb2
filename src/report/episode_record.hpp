// CSV form of the episode records (task/episode_record.hpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "task/episode_record.hpp"

namespace comorph::report {

using task::EpisodeRecord;  // defined in task/episode_record.hpp

// The CSV header, comma separated, in the order the columns are written.
const std::vector<std::string>& episode_csv_columns();

// Largest run log (episodes.csv, evaluations.csv, unpacked) comorph reads: 4300 episodes take ~0.5 MB.
inline constexpr std::size_t kMaxRunLogBytes = 256u << 20;

// CSV with a header row; one row per record. `configurations` is written as
// modules joined by ';' (e.g. "4;2"); success as 0/1; numbers so that reading
// them back gives the same doubles. Text fields may not hold ',', '"' or line
// breaks (throws): the format has no quoting.
void write_episodes_csv(std::ostream& out, const std::vector<EpisodeRecord>& records);
void write_episodes_csv(const std::string& path, const std::vector<EpisodeRecord>& records);

// Reads what write_episodes_csv writes. The header must list the columns
// above (in any order; extra columns are ignored). Refuses an empty file, a
// row with too few or too many fields, a value that is not a number or not
// finite (nan, inf) and an episode whose row appears twice. Errors throw with
// "source:line:column: message" (column = 1-based character position).
std::vector<EpisodeRecord> read_episodes_csv(std::istream& in, const std::string& source_name);
// A path ending in .gz is read as gzip (an exported run's episodes.csv.gz).
std::vector<EpisodeRecord> read_episodes_csv(const std::string& path);

using task::configuration_sequence;  // "4->2" for {4, 2}

}  // namespace comorph::report
