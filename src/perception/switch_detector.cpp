// Scene-switch rule and switch-delay evaluation (switch_detector.hpp).
#include "perception/switch_detector.hpp"

#include "perception/perception_config.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace comorph::perception {

std::string SwitchDetectorParams::validate() const {
  PerceptionConfig config;
  config.switch_detector = *this;
  if (std::string fault = range_fault(config); !fault.empty()) return fault;
  // The range is closed; an agreement of 1 would need more votes than the window has.
  if (agreement >= 1.0) return "switch_detector.agreement must be below 1, got " + std::to_string(agreement);
  return "";
}

int SwitchDetectorParams::votes_needed() const {
  // Strictly more than agreement * window. The tolerance keeps 0.7 * 10 (which
  // is 7.000000000000001 or 6.999999999999999 in binary) at exactly 7.
  const double bound = agreement * window;
  const double rounded = std::round(bound);
  const double b = std::abs(bound - rounded) < 1e-9 ? rounded : bound;
  return static_cast<int>(std::floor(b)) + 1;
}

SwitchDetector::SwitchDetector(const SwitchDetectorParams& params, int initial_scene, int classes)
    : params_(params), classes_(classes) {
  const std::string err = params.validate();
  if (!err.empty()) throw std::invalid_argument(err);
  if (classes < 1) throw std::invalid_argument("SwitchDetector: classes must be >= 1");
  ring_.assign(static_cast<std::size_t>(params.window), kNoLabel);
  counts_.assign(static_cast<std::size_t>(classes), 0);
  reset(initial_scene);
}

void SwitchDetector::reset(int scene) {
  if (scene < 0 || scene >= classes_)
    throw std::invalid_argument("SwitchDetector: scene " + std::to_string(scene) +
                                " is outside 0.." + std::to_string(classes_ - 1));
  scene_ = scene;
  steps_ = 0;
  ring_next_ = 0;
  ring_filled_ = 0;
}

void SwitchDetector::push_label(int label) {
  if (label < kNoLabel || label >= classes_)
    throw std::invalid_argument("SwitchDetector: label " + std::to_string(label) +
                                " is outside 0.." + std::to_string(classes_ - 1));
  ring_[static_cast<std::size_t>(ring_next_)] = label;
  ring_next_ = (ring_next_ + 1) % params_.window;
  if (ring_filled_ < params_.window) ++ring_filled_;
}

SwitchDecision SwitchDetector::step() {
  ++steps_;
  SwitchDecision d;
  d.scene = scene_;
  if (steps_ % params_.interval != 0) return d;
  d.evaluated = true;
  std::fill(counts_.begin(), counts_.end(), 0);
  for (int i = 0; i < ring_filled_; ++i) {
    const int l = ring_[static_cast<std::size_t>(i)];
    if (l != kNoLabel) ++counts_[static_cast<std::size_t>(l)];
  }
  for (int c = 0; c < classes_; ++c)
    if (counts_[static_cast<std::size_t>(c)] > d.votes) {
      d.votes = counts_[static_cast<std::size_t>(c)];
      d.majority = c;
    }
  if (d.majority != kNoLabel && d.majority != scene_ && d.votes >= params_.votes_needed()) {
    scene_ = d.majority;
    d.switched = true;
    d.scene = scene_;
  }
  return d;
}

std::vector<SceneChange> scene_changes(const std::vector<int>& scene_per_step) {
  std::vector<SceneChange> out;
  for (std::size_t i = 1; i < scene_per_step.size(); ++i)
    if (scene_per_step[i] != scene_per_step[i - 1])
      out.push_back({static_cast<long>(i), scene_per_step[i]});
  return out;
}

std::vector<SceneChange> run_detector(const SwitchDetectorParams& params, int initial_scene,
                                      int classes, const std::vector<int>& label_per_step) {
  SwitchDetector detector(params, initial_scene, classes);
  std::vector<SceneChange> out;
  for (std::size_t i = 0; i < label_per_step.size(); ++i) {
    const SwitchDecision d = detector.step(label_per_step[i]);
    if (d.switched) out.push_back({static_cast<long>(i), d.scene});
  }
  return out;
}

double SwitchDelayReport::mean_delay() const {
  if (delays.empty()) return std::numeric_limits<double>::quiet_NaN();
  double sum = 0;
  for (const long d : delays) sum += static_cast<double>(d);
  return sum / static_cast<double>(delays.size());
}

SwitchDelayReport switch_delays(const std::vector<SceneChange>& truth,
                                const std::vector<SceneChange>& declared) {
  SwitchDelayReport r;
  std::vector<bool> used(declared.size(), false);
  for (std::size_t t = 0; t < truth.size(); ++t) {
    const long begin = truth[t].step;
    const long end = t + 1 < truth.size() ? truth[t + 1].step : std::numeric_limits<long>::max();
    bool found = false;
    for (std::size_t k = 0; k < declared.size(); ++k) {
      if (used[k] || declared[k].step < begin || declared[k].step >= end) continue;
      if (declared[k].scene != truth[t].scene) continue;
      used[k] = true;
      r.delays.push_back(declared[k].step - begin);
      found = true;
      break;
    }
    if (found) ++r.detected; else ++r.missed;
  }
  for (const bool u : used)
    if (!u) ++r.false_switches;
  return r;
}

}  // namespace comorph::perception
