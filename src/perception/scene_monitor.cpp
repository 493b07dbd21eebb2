// SceneMonitor (scene_monitor.hpp).
#include "perception/scene_monitor.hpp"

#include <algorithm>

namespace comorph::perception {

SceneMonitor::SceneMonitor(SceneClassifier& classifier, const SwitchDetectorParams& params,
                           int initial_scene)
    : classifier_(classifier),
      detector_(params, initial_scene, classifier.params().classes),
      size_(classifier.params().image_size) {
  const std::size_t frame = static_cast<std::size_t>(size_) * size_;
  ring_.resize(frame * params.window);
  batch_.resize(frame * params.window);
  labels_.reserve(static_cast<std::size_t>(params.window));
}

void SceneMonitor::reset(int scene) {
  detector_.reset(scene);
  next_ = filled_ = 0;
  labels_.clear();
}

SwitchDecision SceneMonitor::step(const float* depth) {
  const int window = detector_.params().window;
  const std::size_t frame = static_cast<std::size_t>(size_) * size_;
  std::copy(depth, depth + frame, ring_.begin() + static_cast<std::ptrdiff_t>(next_ * frame));
  next_ = (next_ + 1) % window;
  filled_ = std::min(filled_ + 1, window);
  if (detector_.evaluates_next()) {
    // Oldest first: the ring's oldest frame sits at next_ once it is full.
    const int first = filled_ == window ? next_ : 0;
    for (int i = 0; i < filled_; ++i) {
      const std::size_t src = static_cast<std::size_t>((first + i) % window) * frame;
      std::copy(ring_.begin() + static_cast<std::ptrdiff_t>(src),
                ring_.begin() + static_cast<std::ptrdiff_t>(src + frame),
                batch_.begin() + static_cast<std::ptrdiff_t>(i * frame));
    }
    labels_.resize(static_cast<std::size_t>(filled_));
    classifier_.classify_batch(batch_.data(), filled_, size_, size_, labels_.data());
    for (const int l : labels_) detector_.push_label(l);
  }
  return detector_.step();
}

}  // namespace comorph::perception
