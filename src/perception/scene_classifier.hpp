// The trained scene classifier, without torch in this header (pimpl): the
// simulation and the trainer include it without paying torch's compile cost.
//
// Saved as a directory:
//   DIR/classifier.pt    the ResNet-18 weights and batch-norm statistics (torch::save)
//   DIR/classifier.yaml  sidecar: format, version, image_size, classes,
//                        class_names, width (what the weights were built for)
// load() rebuilds the net from the sidecar, checks it against the expected
// parameters (if given) and every weight's shape against the net, and throws
// std::runtime_error naming the file and the mismatch.
//
// Threads: the classifier does not change torch's thread count; a program that
// runs small nets calls SceneClassifier::set_threads(1) once (one intra-op
// thread is faster for 16x16 images and keeps results reproducible).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "perception/params.hpp"

namespace comorph::perception {

class SceneClassifier {
 public:
  // Fresh (untrained) weights, initialised from `seed` (torch's global CPU
  // generator is restored afterwards, so other torch users are not disturbed).
  explicit SceneClassifier(const ClassifierParams& params, std::uint64_t seed = 1);
  ~SceneClassifier();
  SceneClassifier(SceneClassifier&&) noexcept;
  SceneClassifier& operator=(SceneClassifier&&) noexcept;

  // Load DIR (see above). `expected`: image_size, classes and width must match
  // it. `device`: where to run ("" = the expected params' device, or "cpu").
  static SceneClassifier load(const std::string& dir, const ClassifierParams* expected = nullptr,
                              const std::string& device = "");
  // Write DIR/classifier.pt and DIR/classifier.yaml (creates DIR; each file is
  // written to a temporary name and renamed, so a crash leaves no half file).
  void save(const std::string& dir) const;

  // Most likely class of one h x w depth image (row-major, depths in [0.01, 1]).
  int classify(const float* depth, int h, int w);
  // Classes of n images stored one after the other (n*h*w floats) in one
  // forward pass (e.g. the last 10 frames); writes n labels.
  void classify_batch(const float* depths, int n, int h, int w, int* labels);
  // Logits of n images; writes n * classes floats (row-major).
  void logits(const float* depths, int n, int h, int w, float* out);

  const ClassifierParams& params() const;
  std::int64_t parameter_count() const;       // trainable weights
  std::vector<float> flat_parameters() const;  // weights then buffers, for comparisons

  // torch's intra-op thread count (at::set_num_threads), for torch-free callers.
  static void set_threads(int threads);

  struct Impl;  // defined in scene_classifier_impl.hpp (torch)
  Impl& impl() { return *impl_; }

 private:
  explicit SceneClassifier(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace comorph::perception
