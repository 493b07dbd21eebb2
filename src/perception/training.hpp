// Supervised training and evaluation of the scene classifier (no torch in this
// header). Adam on the cross-entropy, seeded minibatch shuffling; the held-out
// set is either a separate dataset or a seeded random `eval_fraction` of the
// data. Same seed, same data, one thread -> bit-identical weights.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "perception/dataset.hpp"
#include "perception/params.hpp"
#include "perception/scene_classifier.hpp"

namespace comorph::perception {

// Accuracy and confusion matrix of a classifier on a dataset.
struct EvalResult {
  std::size_t count = 0;   // images evaluated
  double loss = 0;         // mean cross-entropy, nats
  double accuracy = 0;     // fraction correct, 0..1
  // confusion[truth][predicted] = number of images.
  std::vector<std::vector<std::int64_t>> confusion;
  std::vector<double> recall() const;  // per true class, 0..1 (NaN without images)
};

struct EpochStats {
  int epoch = 0;                 // 1-based
  double train_loss = 0;         // mean cross-entropy over the epoch's batches, nats
  double train_accuracy = 0;     // fraction of training images right while training, 0..1
  bool has_eval = false;         // a held-out set exists
  double eval_loss = 0;          // held-out mean cross-entropy, nats
  double eval_accuracy = 0;      // held-out fraction correct, 0..1
  double seconds = 0;            // wall time of the epoch's training part, s
  double images_per_second = 0;  // training throughput, images/s
};

struct TrainResult {
  SceneClassifier model;
  std::vector<EpochStats> epochs;
  std::size_t train_count = 0;  // images trained on
  std::size_t eval_count = 0;   // held-out images (0 = none)
  EvalResult eval;              // final held-out evaluation (count 0 = none)
};

// Called after each epoch (e.g. to print progress); may be empty.
using EpochCallback = std::function<void(const EpochStats&)>;

// Train a fresh classifier. `eval`: separate held-out data (nullptr: hold out
// params.eval_fraction of `data`). Throws std::invalid_argument when the data
// do not fit the parameters (image size, classes, empty sets). With
// train.progress set and no callback, prints one line per epoch to stdout.
TrainResult train_classifier(const Dataset& data, const ClassifierParams& params,
                             const TrainParams& train, const Dataset* eval = nullptr,
                             const EpochCallback& on_epoch = nullptr);

EvalResult evaluate_classifier(SceneClassifier& model, const Dataset& data, int batch_size = 256);

// "accuracy 97.3 % (1234 images)" and the confusion matrix as a text table
// (rows = true class, columns = predicted class, counts of images).
std::string format_evaluation(const EvalResult& result, const ClassifierParams& params);

// One progress line of an epoch, with units.
std::string format_epoch(const EpochStats& e, int epochs);

}  // namespace comorph::perception
