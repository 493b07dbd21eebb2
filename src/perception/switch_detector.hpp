// Scene-switch detector (paper Sec. II-B; docs/perception.md): every
// `interval` control steps, look at the labels of the last `window` frames and
// declare a switch when MORE than `agreement` of them agree on a class other
// than the current scene. Pure C++, no torch, no allocation per step.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace comorph::perception {

inline constexpr int kNoLabel = -1;  // a frame that was not classified

struct SwitchDetectorParams {
  int interval = 100;      // control steps between two decisions (paper: 100)
  int window = 10;         // frame labels looked at per decision (paper: last 10)
  // Fraction of the window that must agree, strictly exceeded (paper: "more
  // than 70 %": 7 of 10 is not a switch, 8 of 10 is). In [0, 1).
  double agreement = 0.7;

  std::string validate() const;  // empty when valid, else names the field
  // Smallest number of agreeing labels that declares a switch.
  int votes_needed() const;
};

// Outcome of one control step.
struct SwitchDecision {
  bool evaluated = false;  // this step was a decision step (every interval-th)
  bool switched = false;   // a new scene was declared
  int scene = 0;           // the current scene after this step
  int majority = kNoLabel; // most frequent label of the window (when evaluated)
  int votes = 0;           // how many window labels agree on `majority`
};

class SwitchDetector {
 public:
  explicit SwitchDetector(const SwitchDetectorParams& params = {}, int initial_scene = 0,
                          int classes = 3);

  // Start an episode in `scene`: clears the labels and the step count.
  void reset(int scene);

  // Record the label of one frame (kNoLabel counts against every class).
  // Keeps the last `window` labels (ring buffer).
  void push_label(int label);
  // Advance one control step; on every interval-th step since reset() the
  // last `window` labels are evaluated. Missing labels (fewer than `window`
  // pushed) count as disagreeing.
  SwitchDecision step();
  // push_label(label) then step(): for a caller that classifies every frame.
  SwitchDecision step(int label) {
    push_label(label);
    return step();
  }
  // True when the next step() evaluates: a caller that classifies only at
  // decisions classifies its last `window` frames now (one batch) and pushes
  // their labels, oldest first, before calling step().
  bool evaluates_next() const { return (steps_ + 1) % params_.interval == 0; }

  int current_scene() const { return scene_; }
  long steps() const { return steps_; }  // control steps since reset()
  const SwitchDetectorParams& params() const { return params_; }

 private:
  SwitchDetectorParams params_;
  int classes_;
  int scene_ = 0;
  long steps_ = 0;
  std::vector<int> ring_;     // last `window` labels
  int ring_next_ = 0;         // where the next label goes
  int ring_filled_ = 0;       // labels held (<= window)
  std::vector<int> counts_;   // per-class vote counts (reused)
};

// ---- evaluation helpers: switch delay ----

struct SceneChange {
  long step;  // control step at which the change happens
  int scene;  // the new scene
};

// Steps at which `scene_per_step` changes value (index i = control step i).
std::vector<SceneChange> scene_changes(const std::vector<int>& scene_per_step);

// Run a detector over per-step labels (kNoLabel where not classified);
// returns the declared switches (step = index of the deciding step).
std::vector<SceneChange> run_detector(const SwitchDetectorParams& params, int initial_scene,
                                      int classes, const std::vector<int>& label_per_step);

struct SwitchDelayReport {
  std::vector<long> delays;  // control steps from each detected change to its declaration
  int detected = 0;          // true changes followed by a declaration of the same scene
  int missed = 0;            // true changes with no such declaration before the next change
  int false_switches = 0;    // declarations that match no true change
  double mean_delay() const;  // control steps; NaN when nothing was detected
};

// Match declared switches to the true changes: a change to scene s at step t
// is detected by the first declaration of s at a step in [t, next change).
SwitchDelayReport switch_delays(const std::vector<SceneChange>& truth,
                                const std::vector<SceneChange>& declared);

}  // namespace comorph::perception
