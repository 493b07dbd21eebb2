// Synthetic depth images (synthetic.hpp). Own uniform/normal draws so the
// images are the same with every standard library.
#include "perception/synthetic.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "perception/params.hpp"

namespace comorph::perception {
namespace {

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}
  double uniform(double lo, double hi) {
    return lo + (hi - lo) * static_cast<double>(engine_() >> 11) * 0x1.0p-53;
  }
  int integer(int lo, int hi) {  // inclusive
    return lo + static_cast<int>(engine_() % static_cast<std::uint64_t>(hi - lo + 1));
  }
  double normal() {  // Box-Muller
    const double u1 = uniform(1e-12, 1.0), u2 = uniform(0.0, 1.0);
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }

 private:
  std::mt19937_64 engine_;
};

// Ground seen from the robot: near at the bottom row, far at the horizon row,
// nothing (1.0) above it.
void ground(float* img, int n, Rng& rng) {
  const int horizon = rng.integer(n / 8, n / 3);
  const double near = rng.uniform(0.12, 0.3), far = rng.uniform(0.6, 0.95);
  for (int r = 0; r < n; ++r) {
    double d = 1.0;
    if (r >= horizon) {
      const double t = static_cast<double>(n - 1 - r) / std::max(1, n - 1 - horizon);
      d = near + (far - near) * t * t;  // perspective: depth grows faster near the horizon
    }
    for (int c = 0; c < n; ++c) img[r * n + c] = static_cast<float>(d);
  }
}

void stairs(float* img, int n, Rng& rng) {
  ground(img, n, rng);
  int row = n - 1 - rng.integer(n / 8, n / 3);  // bottom edge of the first riser
  double depth = rng.uniform(0.15, 0.5);
  const double rise = rng.uniform(0.06, 0.15);  // depth added per step
  const double tilt = rng.uniform(-0.01, 0.01); // slight yaw of the staircase
  while (row >= 0) {
    const int height = rng.integer(std::max(2, n / 8), std::max(3, n / 4));
    for (int r = std::max(0, row - height + 1); r <= row; ++r)
      for (int c = 0; c < n; ++c)
        img[r * n + c] = static_cast<float>(std::min(1.0, depth + tilt * (c - n / 2)));
    row -= height;
    depth += rise;
  }
}

void obstacles(float* img, int n, Rng& rng) {
  ground(img, n, rng);
  const int boxes = rng.integer(1, 3);
  for (int b = 0; b < boxes; ++b) {
    const int w = rng.integer(std::max(3, n / 5), std::max(4, (3 * n) / 8));
    const int h = rng.integer(std::max(3, n / 5), std::max(4, (3 * n) / 8));
    const int bottom = rng.integer(n / 2, n - 1);
    const int left = rng.integer(0, n - w);
    // The box's front face is a little nearer than the ground it stands on.
    const float d = static_cast<float>(std::max(0.01, img[bottom * n + left] - rng.uniform(0.05, 0.12)));
    for (int r = std::max(0, bottom - h + 1); r <= bottom; ++r)
      for (int c = left; c < left + w; ++c) img[r * n + c] = std::min(img[r * n + c], d);
  }
}

void target_zone(float* img, int n, Rng& rng) {
  ground(img, n, rng);
  if (rng.uniform(0, 1) < 0.5) {  // a thin far post marks the target
    const int c = rng.integer(0, n - 1);
    const int top = rng.integer(0, n / 2);
    const float d = static_cast<float>(rng.uniform(0.7, 0.95));
    for (int r = top; r < std::min(n, top + n / 3); ++r) img[r * n + c] = std::min(img[r * n + c], d);
  }
}

}  // namespace

Dataset make_synthetic_dataset(const SyntheticParams& p) {
  if (p.image_size < 8) throw std::invalid_argument("synthetic: image_size must be >= 8 pixels");
  if (p.count < 0) throw std::invalid_argument("synthetic: count must be >= 0");
  if (p.noise < 0) throw std::invalid_argument("synthetic: noise must be >= 0");
  const int n = p.image_size;
  Dataset data(n, n, 3);
  data.images.reserve(static_cast<std::size_t>(p.count) * data.pixels());
  data.labels.reserve(static_cast<std::size_t>(p.count));
  Rng rng(p.seed);
  std::vector<float> img(data.pixels());
  for (int i = 0; i < p.count; ++i) {
    const int label = i % 3;
    if (label == kStairs) stairs(img.data(), n, rng);
    else if (label == kObstacleField) obstacles(img.data(), n, rng);
    else target_zone(img.data(), n, rng);
    for (float& v : img)
      v = static_cast<float>(std::clamp(v + p.noise * rng.normal(), 0.01, 1.0));
    data.add(img.data(), label);
  }
  return data;
}

}  // namespace comorph::perception
