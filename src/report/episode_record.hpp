// One line per episode: what the trainer and the evaluator log, what the
// metrics and the training curves are computed from. No MuJoCo here.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace comorph::report {

struct EpisodeRecord {
  int episode = 0;                 // episode index within its run (training or evaluation)
  std::uint64_t seed = 0;          // seed the episode's scene was drawn from
  std::string scenario;            // default | obstacles7 | obstacles8 | mixed | ...
  double stair_height_m = 0;       // stair height of this episode, metres (0.04, 0.06, 0.08)
  int obstacles = 0;               // obstacles in the flat area
  bool success = false;            // reached the target
  std::string termination;         // why it ended: success, collision, overturn, off_stairs, battery, timeout, ...
  double time_s = 0;               // simulated time used, seconds
  double energy_J = 0;             // energy drawn from all batteries, joules
  double distance_fraction = 0;    // D: distance covered / initial distance to the target, 0..1
  double return_R1 = 0;            // sum of the motion reward R1 (Eq. 6) over the episode
  std::vector<int> configurations; // modules of each configuration chosen, in order (e.g. 4 then 2)
  int modules_total = 0;           // modules (batteries) on board at the start of the episode
};

// The CSV header, comma separated, in the order the columns are written.
const std::vector<std::string>& episode_csv_columns();

// CSV with a header row; one row per record. `configurations` is written as
// modules joined by ';' (e.g. "4;2"); success as 0/1; numbers so that reading
// them back gives the same doubles. Text fields may not hold ',', '"' or line
// breaks (throws): the format has no quoting.
void write_episodes_csv(std::ostream& out, const std::vector<EpisodeRecord>& records);
void write_episodes_csv(const std::string& path, const std::vector<EpisodeRecord>& records);

// Reads what write_episodes_csv writes. The header must list the columns
// above (in any order; extra columns are ignored). Errors throw with
// "source:line:column: message" (column = 1-based character position).
std::vector<EpisodeRecord> read_episodes_csv(std::istream& in, const std::string& source_name);
std::vector<EpisodeRecord> read_episodes_csv(const std::string& path);

// "4->2" for {4, 2}; "" for none.
std::string configuration_sequence(const std::vector<int>& configurations);

}  // namespace comorph::report
