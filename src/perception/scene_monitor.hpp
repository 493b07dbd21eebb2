// The perception loop of one robot (paper Fig. 2): keep the last `window`
// depth frames, and on every decision step classify them in ONE batch and let
// the switch detector decide. No torch in this header; no allocation per step
// (the frame ring and the label buffer are allocated once).
//
//   SceneMonitor monitor(classifier, detector_params, initial_scene);
//   each control step:  SwitchDecision d = monitor.step(depth);   // h*w floats
//                       if (d.switched) ... ask the configuration model ...
#pragma once

#include <vector>

#include "perception/scene_classifier.hpp"
#include "perception/switch_detector.hpp"

namespace comorph::perception {

class SceneMonitor {
 public:
  // `classifier` must outlive the monitor.
  SceneMonitor(SceneClassifier& classifier, const SwitchDetectorParams& params, int initial_scene);

  void reset(int scene);  // new episode: forget frames and steps
  // One control step with this step's depth image (image_size^2 floats).
  SwitchDecision step(const float* depth);

  int current_scene() const { return detector_.current_scene(); }
  // Labels of the last decision's frames, oldest first (empty before one).
  const std::vector<int>& last_labels() const { return labels_; }
  const SwitchDetector& detector() const { return detector_; }

 private:
  SceneClassifier& classifier_;
  SwitchDetector detector_;
  int size_;                   // pixels a side
  std::vector<float> ring_;    // window frames
  std::vector<float> batch_;   // the window frames in time order, for one forward pass
  std::vector<int> labels_;
  int next_ = 0, filled_ = 0;
};

}  // namespace comorph::perception
