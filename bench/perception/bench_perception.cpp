// Perception on this CPU, one intra-op thread (as the trainer runs it):
//  - classify latency for 1 frame and for the 10-frame window, ms per call;
//  - training throughput (forward + backward + Adam, batch 64), images/s;
//  - each compared with a bare float matmul of the same FLOPs, so the ratio
//    says how far the small convolutions are from the BLAS peak.
// Widths 16 (the CPU default) and 64 (the standard ResNet-18), 16x16 images.
#include <fmt/format.h>
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <vector>

#include "perception/scene_classifier.hpp"
#include "perception/synthetic.hpp"
#include "perception/training.hpp"

namespace cp = comorph::perception;
using Clock = std::chrono::steady_clock;

namespace {

// Multiply-adds x 2 of one forward pass of the ResNet-18 of resnet.hpp.
double forward_flops(int width, int size, int classes) {
  auto conv = [](double cin, double cout, double k, double hout) { return 2 * cin * cout * k * k * hout * hout; };
  double f = conv(1, width, 3, size);  // stem
  int c = width, h = size;
  for (int stage = 0; stage < 4; ++stage) {
    const int out = width << stage;
    const int ho = stage == 0 ? h : h / 2;
    f += conv(c, out, 3, ho) + conv(out, out, 3, ho);              // block 1
    if (c != out || ho != h) f += conv(c, out, 1, ho);              // its shortcut
    f += 2 * conv(out, out, 3, ho);                                // block 2
    c = out;
    h = ho;
  }
  return f + 2.0 * c * classes;
}

// Median seconds of `fn` over `reps` calls after 3 warm-up calls.
template <typename F>
double median_seconds(int reps, F&& fn) {
  for (int i = 0; i < 3; ++i) fn();
  std::vector<double> t;
  for (int i = 0; i < reps; ++i) {
    const auto s = Clock::now();
    fn();
    t.push_back(std::chrono::duration<double>(Clock::now() - s).count());
  }
  std::nth_element(t.begin(), t.begin() + reps / 2, t.end());
  return t[static_cast<std::size_t>(reps / 2)];
}

// Seconds of a square float matmul with about `flops` FLOPs.
double matmul_seconds(double flops) {
  const auto n = static_cast<std::int64_t>(std::max(8.0, std::cbrt(flops / 2.0)));
  const torch::Tensor a = torch::randn({n, n}), b = torch::randn({n, n});
  torch::Tensor c = torch::empty({n, n});
  const double s = median_seconds(50, [&] { torch::mm_out(c, a, b); });
  return s * flops / (2.0 * static_cast<double>(n * n * n));
}

}  // namespace

int main() {
  cp::SceneClassifier::set_threads(1);
  const int size = 16;
  cp::SyntheticParams sp;
  sp.count = 640;
  const cp::Dataset data = cp::make_synthetic_dataset(sp);

  fmt::print("perception bench: 16x16 depth, 3 classes, 1 thread\n");
  fmt::print("{:>6} {:>9} {:>10} | {:>12} {:>8} | {:>12} {:>8} | {:>12} {:>8}\n", "width", "weights",
             "MFLOP/img", "1 frame ms", "x matmul", "10 frames ms", "x matmul", "train img/s", "x matmul");
  for (const int width : {16, 64}) {
    cp::ClassifierParams p;
    p.width = width;
    cp::SceneClassifier model(p);
    const double flops = forward_flops(width, size, 3);
    int labels[10];
    const double t1 = median_seconds(200, [&] { model.classify(data.image(0), size, size); });
    const double t10 = median_seconds(100, [&] { model.classify_batch(data.image(0), 10, size, size, labels); });

    cp::TrainParams tp;
    tp.epochs = 1;
    tp.batch_size = 64;
    tp.eval_fraction = 0;
    tp.progress = false;
    const cp::TrainResult r = cp::train_classifier(data, p, tp);
    const double train_ips = r.epochs.back().images_per_second;
    // Training ~ 3x the forward FLOPs (forward, input grads, weight grads).
    const double train_matmul_ips = 1.0 / matmul_seconds(3 * flops);

    fmt::print("{:>6} {:>8.2f}M {:>10.1f} | {:>12.3f} {:>8.1f} | {:>12.3f} {:>8.1f} | {:>12.0f} {:>8.1f}\n", width,
               static_cast<double>(model.parameter_count()) / 1e6, flops / 1e6, 1e3 * t1,
               t1 / matmul_seconds(flops), 1e3 * t10, t10 / matmul_seconds(10 * flops), train_ips,
               train_matmul_ips / train_ips);
  }
  fmt::print("x matmul = time / time of a bare float matmul of the same FLOPs (1.0 = BLAS peak)\n");
  return 0;
}
