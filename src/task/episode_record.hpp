// One line per episode: what the trainer and the evaluator log and what the
// metrics and training curves (src/report) are computed from. Plain data here,
// below both, so the trainer's log and the report's record are one type.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace comorph::task {

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
  bool stairs_climbed = false;     // every module reached the top of the stairs (the flat area)
  double action_saturation = 0;    // share of executed motion-action components at the bound (|a| >= 0.99), 0..1
};

// "4->2" for {4, 2}; "" for none: how logs, progress lines and reports name a
// sequence of configurations.
inline std::string configuration_sequence(const std::vector<int>& configurations) {
  std::string s;
  for (int modules : configurations) s += (s.empty() ? "" : "->") + std::to_string(modules);
  return s;
}

}  // namespace comorph::task
