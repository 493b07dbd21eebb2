// Switch delay of the whole perception loop (classifier + detector) on scene
// changes assembled from a labelled dataset, without the simulator: each trial
// is an episode of `steps` control steps in scene A that changes to scene B at
// a random step; every step shows a random image of the true scene. Frames are
// drawn independently (a real camera's frames are correlated, so this measures
// the rule and the classifier's errors, not the robot's motion).
#pragma once

#include <cstdint>
#include <string>

#include "perception/dataset.hpp"
#include "perception/scene_classifier.hpp"
#include "perception/switch_detector.hpp"

namespace comorph::perception {

struct SwitchTrialParams {
  int trials = 100;            // episodes, each with one true scene change
  int steps = 600;             // control steps per episode
  int earliest_change = 100;   // the change happens uniformly in [earliest, latest) steps
  int latest_change = 400;
  std::uint64_t seed = 1;      // scenes, change steps and frames
};

struct SwitchTrialReport {
  SwitchDelayReport delays;    // pooled over all trials (delays in control steps)
  int trials = 0;
  double max_delay = 0;        // control steps
};

// Throws std::invalid_argument when the dataset lacks images of a class or
// does not fit the classifier.
SwitchTrialReport evaluate_switching(SceneClassifier& classifier, const Dataset& data,
                                     const SwitchDetectorParams& detector,
                                     const SwitchTrialParams& trials);

// "switch delay: mean 58.3 control steps (max 149), 100 of 100 changes detected, 0 missed,
//  0 false switches"
std::string format_switch_report(const SwitchTrialReport& report);

}  // namespace comorph::perception
