// A synthetic 3-class depth task for tests, benchmarks and trying the
// `classifier` command without the simulator. Images mimic a forward-looking
// depth camera (row 0 = top, depth in [0.01, 1], 1 = far/nothing):
//   0 stairs:         ground, then full-width horizontal bands (risers) whose
//                     depth grows step by step: horizontal step edges;
//   1 obstacle field: ground gradient with 1..3 near boxes standing on it;
//   2 target zone:    open ground gradient to a far horizon (a thin far post).
// Every shape parameter is random, plus Gaussian pixel noise.
#pragma once

#include <cstdint>

#include "perception/dataset.hpp"

namespace comorph::perception {

struct SyntheticParams {
  int count = 600;          // images (labels cycle 0, 1, 2, ...: balanced)
  int image_size = 16;      // H = W, pixels (>= 8)
  double noise = 0.03;      // std of additive Gaussian depth noise (depth units)
  std::uint64_t seed = 1;   // same seed -> same images
};

Dataset make_synthetic_dataset(const SyntheticParams& params);

}  // namespace comorph::perception
