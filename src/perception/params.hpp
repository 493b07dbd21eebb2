// Parameters of the scene classifier and of its training (no torch here).
// Defaults are the CPU preset of configs/perception.yaml; docs/perception.md
// says why each one is what it is.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace comorph::perception {

// Scene classes of the default 3-class task (labels written by the simulator).
inline constexpr int kStairs = 0;         // stairs ahead
inline constexpr int kObstacleField = 1;  // flat ground with obstacles
inline constexpr int kTargetZone = 2;     // open ground, target in view

// Architecture of the classifier: a ResNet-18 (BasicBlock x [2, 2, 2, 2], batch
// norm) with a one-channel depth input and a CIFAR-style stem (3x3 conv,
// stride 1, no max-pool) because the images are tiny (16x16 by default).
struct ClassifierParams {
  int image_size = 16;  // H = W of the depth image, pixels (8..256)
  int classes = 3;      // number of scene classes (2..255)
  // Names of the classes, one per class (empty: "class 0", "class 1", ...).
  std::vector<std::string> class_names{"stairs", "obstacle_field", "target_zone"};
  // Channels of the first stage; stages have width, 2w, 4w, 8w channels.
  // 64 is the standard ResNet-18 (11.2 M weights, 277 MFLOP per 16x16 image);
  // the CPU default 16 (0.7 M weights, 17 MFLOP) trains ~10x faster (~500 vs
  // ~46 images/s on one core) and classifies the 10-frame window in ~4 ms
  // instead of ~60 ms (bench/perception); 3 classes of 16x16 images need no more.
  int width = 16;
  std::string device = "cpu";  // torch device string: "cpu", "cuda", "cuda:1"

  // Empty when valid, otherwise the first fault (names the field).
  std::string validate() const;
  // Name of class `c` (class_names[c], or "class c").
  std::string class_name(int c) const;
};

// Supervised training of the classifier (train_classifier in training.hpp).
struct TrainParams {
  int epochs = 10;               // passes over the training set
  int batch_size = 64;           // images per Adam step
  double learning_rate = 1e-3;   // Adam step size at the start
  // Cosine decay of the step size from learning_rate to 0 over all batches:
  // the last epochs settle instead of ending on a noisy step.
  bool cosine_schedule = true;
  double weight_decay = 1e-4;    // L2 penalty of Adam (1/weight units^2)
  // Fraction of the data held out for evaluation when no separate evaluation
  // dataset is given (0 = no held-out set). The split is seeded.
  double eval_fraction = 0.2;
  std::uint64_t seed = 1;        // weight init, split and minibatch shuffling
  // Intra-op threads for torch. 1 by default: the nets are small, so more
  // threads mostly add synchronisation and break bit-exact reproducibility.
  int threads = 1;
  bool progress = true;          // print one line per epoch (stdout)

  std::string validate() const;
};

}  // namespace comorph::perception
