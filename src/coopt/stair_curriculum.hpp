// The stair-height curriculum (trainer.stair_curriculum): a share of the
// training episodes takes its stair height in proportion to how often the
// run has recently failed at each height, the rest uniformly, as
// prioritised level sampling does (Jiang et al., ICML 2021). It reads only
// the run's own outcomes: no knowledge of which height is hard.
// The warm-up, the DQN refit and every evaluation keep the scene's own draw.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace comorph::coopt {

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
  // The remembered outcomes as text for a checkpoint ('1' success, '0'
  // failure, heights separated by ','), and back; a malformed text throws.
  std::string outcomes_text() const;
  void set_outcomes_text(const std::string& text);

 private:
  std::vector<double> heights_;
  int window_ = 0;
  std::vector<std::string> outcomes_;  // per height, oldest first, at most window_
};

}  // namespace comorph::coopt
