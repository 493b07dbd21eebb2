// Switch-delay trials of the perception loop (switch_evaluation.hpp).
#include "perception/switch_evaluation.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <random>
#include <stdexcept>
#include <vector>

#include "perception/scene_monitor.hpp"

namespace comorph::perception {

SwitchTrialReport evaluate_switching(SceneClassifier& classifier, const Dataset& data,
                                     const SwitchDetectorParams& detector,
                                     const SwitchTrialParams& t) {
  const ClassifierParams& p = classifier.params();
  if (data.height != p.image_size || data.width != p.image_size || data.classes != p.classes)
    throw std::invalid_argument("switch trials: the dataset does not fit the classifier");
  if (t.trials < 1 || t.earliest_change < 1 || t.latest_change <= t.earliest_change ||
      t.latest_change > t.steps)
    throw std::invalid_argument("switch trials: need trials >= 1 and 1 <= earliest < latest <= steps");
  std::vector<std::vector<std::size_t>> by_class(static_cast<std::size_t>(p.classes));
  for (std::size_t i = 0; i < data.size(); ++i) by_class[data.labels[i]].push_back(i);
  for (int c = 0; c < p.classes; ++c)
    if (by_class[static_cast<std::size_t>(c)].empty())
      throw std::invalid_argument("switch trials: the dataset has no image of " + p.class_name(c));

  std::mt19937_64 rng(t.seed);
  auto below = [&](std::size_t n) { return static_cast<std::size_t>(rng() % n); };
  SceneMonitor monitor(classifier, detector, 0);
  SwitchTrialReport report;
  report.trials = t.trials;
  for (int trial = 0; trial < t.trials; ++trial) {
    const int from = static_cast<int>(below(static_cast<std::size_t>(p.classes)));
    const int to = (from + 1 + static_cast<int>(below(static_cast<std::size_t>(p.classes - 1)))) % p.classes;
    const int change = t.earliest_change +
                       static_cast<int>(below(static_cast<std::size_t>(t.latest_change - t.earliest_change)));
    monitor.reset(from);
    std::vector<SceneChange> declared;
    for (int step = 0; step < t.steps; ++step) {
      const auto& pool = by_class[static_cast<std::size_t>(step < change ? from : to)];
      const SwitchDecision d = monitor.step(data.image(pool[below(pool.size())]));
      if (d.switched) declared.push_back({step, d.scene});
    }
    // Matched per trial, then pooled.
    const SwitchDelayReport one = switch_delays({{change, to}}, declared);
    report.delays.delays.insert(report.delays.delays.end(), one.delays.begin(), one.delays.end());
    report.delays.detected += one.detected;
    report.delays.missed += one.missed;
    report.delays.false_switches += one.false_switches;
  }
  for (const long d : report.delays.delays) report.max_delay = std::max(report.max_delay, static_cast<double>(d));
  return report;
}

std::string format_switch_report(const SwitchTrialReport& r) {
  const SwitchDelayReport& d = r.delays;
  return fmt::format(
      "switch delay: mean {:.1f} control steps (max {:.0f}) over {} trials; {} of {} scene changes "
      "detected, {} missed, {} false switches\n",
      d.mean_delay(), r.max_delay, r.trials, d.detected, d.detected + d.missed, d.missed,
      d.false_switches);
}

}  // namespace comorph::perception
