// The training curricula: which scene (and which first chain) a training
// episode plays, from the run's own recent outcomes only: no knowledge of
// which height or chain is hard. The warm-up, the DQN refit and every
// evaluation keep the scene's own draw.
//
// - StairCurriculum (trainer.stair_curriculum): a share of the training
//   episodes takes its stair height in proportion to how often the run has
//   recently failed at each height, the rest uniformly, as prioritised level
//   sampling does (Jiang et al., ICML 2021).
// - ChainCurriculum (trainer.chain_curriculum): a share of the training
//   episodes plays a (stair height, first chain) pair drawn in proportion to
//   p (1 - p), p the share of the pair's recent episodes whose first chain
//   climbed the stairs: most where the outcome is least certain, a floor where
//   the run always or never climbs ("goals of intermediate difficulty",
//   Florensa et al., ICML 2018). The DQN settles on a chain per height early,
//   and the motion model then practises only those; the choice of body can
//   only follow which chains the motion model happened to learn to climb with.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace comorph::coopt {

// The uniform number in [0, 1) that one episode's stream (coopt::stream_seed) draws: every curriculum's draw.
double uniform_from(std::uint64_t seed);

// The last `window` outcomes (success or not) of each of `keys` kinds of
// episode, and their text for a checkpoint ('1' / '0', keys separated by ',').
class OutcomeWindows {
 public:
  OutcomeWindows() = default;
  OutcomeWindows(std::size_t keys, int window);
  void record(std::size_t key, bool success);
  // The key's share of successes over its window; `if_empty` before its first outcome.
  double success_rate(std::size_t key, double if_empty) const;
  std::string text() const;
  // A malformed text throws; `option` names the window's setting in the message.
  void set_text(const std::string& text, const std::string& option);

 private:
  int window_ = 0;
  std::vector<std::string> outcomes_;  // per key, oldest first, at most window_
};

class StairCurriculum {
 public:
  StairCurriculum() = default;
  // `heights_m`: the run's distinct stair heights (coopt::stair_heights);
  // `window`: the outcomes remembered per height.
  StairCurriculum(std::vector<double> heights_m, int window);

  // A training episode at `height_m` ended, with or without success.
  void record(double height_m, bool success);
  // Each height's failure rate over its window; 1 before its first episode.
  std::vector<double> failure_rates() const;
  // Draw probabilities per height: (1 - share) uniform + share in proportion
  // to the failure rates (uniform while none fails).
  std::vector<double> weights(double share) const;
  // The height `weights` gives uniform number u in [0, 1).
  double height_at(const std::vector<double>& weights, double u) const;
  // The height of an episode from its own stream (coopt::stream_seed).
  double draw(const std::vector<double>& weights, std::uint64_t seed) const;

  const std::vector<double>& heights() const { return heights_; }
  // The remembered outcomes as text for a checkpoint, and back; a malformed text throws.
  std::string outcomes_text() const { return outcomes_.text(); }
  void set_outcomes_text(const std::string& text) { outcomes_.set_text(text, "trainer.stair_curriculum_window"); }

 private:
  std::vector<double> heights_;
  OutcomeWindows outcomes_;  // per height
};

class ChainCurriculum {
 public:
  // A pair's weight where the run always or never climbs, against 0.25 where it climbs half the time.
  static constexpr double kFloor = 0.01;

  struct Pair {
    double height_m = 0;
    int modules = 0;  // the first configuration's chain length
  };

  ChainCurriculum() = default;
  // `heights_m`: the run's distinct stair heights; chains of min_modules..max_modules;
  // `window`: the outcomes remembered per pair.
  ChainCurriculum(std::vector<double> heights_m, int min_modules, int max_modules, int window);

  // A training episode at `height_m` whose first chain had `modules` modules
  // ended, with its stairs climbed or not.
  void record(double height_m, int modules, bool climbed);
  // Each pair's share of climbs over its window (height-major, then chain
  // length); -1 before its first episode.
  std::vector<double> climb_rates() const;
  // Draw probabilities per pair, in proportion to max(p (1 - p), kFloor); a
  // pair not yet played counts as p = 0.5.
  std::vector<double> weights() const;
  // The pair `weights` gives uniform number u in [0, 1).
  Pair pair_at(const std::vector<double>& weights, double u) const;
  // The pair of an episode from its own stream (coopt::stream_seed).
  Pair draw(const std::vector<double>& weights, std::uint64_t seed) const;

  std::size_t pairs() const { return heights_.size() * static_cast<std::size_t>(chains_); }
  std::string outcomes_text() const { return outcomes_.text(); }
  void set_outcomes_text(const std::string& text) { outcomes_.set_text(text, "trainer.chain_curriculum_window"); }

 private:
  std::vector<double> heights_;
  int min_modules_ = 0;
  int chains_ = 0;
  OutcomeWindows outcomes_;  // per pair
};

}  // namespace comorph::coopt
