// Training loop and evaluation of the scene classifier (training.hpp).
#include "perception/training.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>

#include "perception/scene_classifier_impl.hpp"

namespace comorph::perception {
namespace {

void check_data(const Dataset& d, const ClassifierParams& p, const std::string& what) {
  if (d.size() == 0) throw std::invalid_argument(what + " dataset is empty");
  if (d.height != p.image_size || d.width != p.image_size)
    throw std::invalid_argument(what + " dataset images are " + std::to_string(d.height) + "x" +
                                std::to_string(d.width) + " pixels, the classifier expects " +
                                std::to_string(p.image_size) + "x" + std::to_string(p.image_size));
  if (d.classes != p.classes)
    throw std::invalid_argument(what + " dataset has " + std::to_string(d.classes) +
                                " classes, the classifier " + std::to_string(p.classes));
  if (d.images.size() != d.size() * d.pixels())
    throw std::invalid_argument(what + " dataset: image buffer size does not match the labels");
}

// Fisher-Yates with the raw engine: the same order with every standard library.
void shuffle(std::vector<std::int64_t>& v, std::mt19937_64& rng) {
  for (std::size_t i = v.size(); i > 1; --i) std::swap(v[i - 1], v[rng() % i]);
}

struct Tensors {
  torch::Tensor images;  // N x 1 x H x W, float, on the device
  torch::Tensor labels;  // N, int64, on the device
};

Tensors to_tensors(const Dataset& d, torch::Device device) {
  const auto n = static_cast<std::int64_t>(d.size());
  Tensors t;
  t.images = torch::from_blob(const_cast<float*>(d.images.data()), {n, 1, d.height, d.width},
                              torch::kFloat32)
                 .to(device, /*non_blocking=*/false, /*copy=*/true);
  t.labels = torch::from_blob(const_cast<std::uint8_t*>(d.labels.data()), {n}, torch::kUInt8)
                 .to(device, torch::kInt64, false, true);
  return t;
}

EvalResult evaluate_tensors(ResNet18& net, const Tensors& t, int classes, int batch_size) {
  torch::InferenceMode guard;
  net->eval();
  const std::int64_t n = t.images.size(0);
  EvalResult r;
  r.count = static_cast<std::size_t>(n);
  r.confusion.assign(static_cast<std::size_t>(classes), std::vector<std::int64_t>(classes, 0));
  double loss_sum = 0;
  std::int64_t correct = 0;
  for (std::int64_t begin = 0; begin < n; begin += batch_size) {
    const std::int64_t end = std::min(n, begin + batch_size);
    const torch::Tensor x = t.images.slice(0, begin, end), y = t.labels.slice(0, begin, end);
    const torch::Tensor logits = net->forward(x);
    loss_sum += torch::nn::functional::cross_entropy(
                    logits, y, torch::nn::functional::CrossEntropyFuncOptions().reduction(torch::kSum))
                    .item<double>();
    const torch::Tensor pred = logits.argmax(1).to(torch::kCPU);
    const torch::Tensor truth = y.to(torch::kCPU);
    const auto* p = pred.data_ptr<std::int64_t>();
    const auto* g = truth.data_ptr<std::int64_t>();
    for (std::int64_t i = 0; i < end - begin; ++i) {
      ++r.confusion[static_cast<std::size_t>(g[i])][static_cast<std::size_t>(p[i])];
      correct += p[i] == g[i];
    }
  }
  r.loss = loss_sum / static_cast<double>(n);
  r.accuracy = static_cast<double>(correct) / static_cast<double>(n);
  return r;
}

}  // namespace

std::vector<double> EvalResult::recall() const {
  std::vector<double> out;
  for (std::size_t c = 0; c < confusion.size(); ++c) {
    const std::int64_t total = std::accumulate(confusion[c].begin(), confusion[c].end(), std::int64_t{0});
    out.push_back(total ? static_cast<double>(confusion[c][c]) / static_cast<double>(total)
                        : std::numeric_limits<double>::quiet_NaN());
  }
  return out;
}

EvalResult evaluate_classifier(SceneClassifier& model, const Dataset& data, int batch_size) {
  auto& m = model.impl();
  check_data(data, m.params, "evaluation");
  if (batch_size < 1) throw std::invalid_argument("evaluation batch_size must be >= 1");
  return evaluate_tensors(m.net, to_tensors(data, m.device), m.params.classes, batch_size);
}

TrainResult train_classifier(const Dataset& data, const ClassifierParams& params,
                             const TrainParams& tp, const Dataset* eval_data,
                             const EpochCallback& on_epoch) {
  for (const std::string& err : {params.validate(), tp.validate()})
    if (!err.empty()) throw std::invalid_argument(err);
  check_data(data, params, "training");
  if (eval_data) check_data(*eval_data, params, "evaluation");
  at::set_num_threads(tp.threads);

  // Held-out split: a seeded permutation; its first eval_fraction is held out.
  std::mt19937_64 rng(tp.seed);
  Dataset split_train, split_eval;
  const Dataset* train_set = &data;
  const Dataset* eval_set = eval_data;
  if (!eval_data && tp.eval_fraction > 0) {
    std::vector<std::int64_t> order(data.size());
    std::iota(order.begin(), order.end(), 0);
    shuffle(order, rng);
    const auto held = static_cast<std::size_t>(std::llround(tp.eval_fraction * data.size()));
    if (held == 0 || held >= data.size())
      throw std::invalid_argument("eval_fraction " + std::to_string(tp.eval_fraction) + " of " +
                                  std::to_string(data.size()) + " images leaves an empty set");
    split_eval = data.subset({order.begin(), order.begin() + static_cast<std::ptrdiff_t>(held)});
    split_train = data.subset({order.begin() + static_cast<std::ptrdiff_t>(held), order.end()});
    train_set = &split_train;
    eval_set = &split_eval;
  }

  TrainResult result{SceneClassifier(params, tp.seed), {}, train_set->size(),
                     eval_set ? eval_set->size() : 0, {}};
  auto& m = result.model.impl();
  const Tensors train = to_tensors(*train_set, m.device);
  Tensors held;
  if (eval_set) held = to_tensors(*eval_set, m.device);

  torch::optim::Adam optimizer(
      m.net->parameters(),
      torch::optim::AdamOptions(tp.learning_rate).weight_decay(tp.weight_decay));
  const auto n = static_cast<std::int64_t>(train_set->size());
  std::vector<std::int64_t> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  torch::Tensor index = torch::empty({n}, torch::kInt64);
  const std::int64_t batches_per_epoch = (n + tp.batch_size - 1) / tp.batch_size;
  const double total_batches = static_cast<double>(batches_per_epoch) * tp.epochs;
  std::int64_t batch_number = 0;

  for (int epoch = 1; epoch <= tp.epochs; ++epoch) {
    const auto start = std::chrono::steady_clock::now();
    shuffle(order, rng);
    std::copy(order.begin(), order.end(), index.data_ptr<std::int64_t>());
    const torch::Tensor device_index = index.to(m.device);
    m.net->train();
    double loss_sum = 0;
    std::int64_t correct = 0, seen = 0;
    for (std::int64_t begin = 0; begin < n; begin += tp.batch_size) {
      const std::int64_t end = std::min(n, begin + tp.batch_size);
      if (end - begin < 2 && begin > 0) break;  // batch norm needs 2 images; drop a lone last one
      const torch::Tensor idx = device_index.slice(0, begin, end);
      const torch::Tensor x = train.images.index_select(0, idx);
      const torch::Tensor y = train.labels.index_select(0, idx);
      if (tp.cosine_schedule) {
        const double lr = 0.5 * tp.learning_rate *
                          (1.0 + std::cos(3.141592653589793 * static_cast<double>(batch_number) / total_batches));
        for (auto& group : optimizer.param_groups())
          static_cast<torch::optim::AdamOptions&>(group.options()).lr(lr);
      }
      ++batch_number;
      optimizer.zero_grad();
      const torch::Tensor logits = m.net->forward(x);
      const torch::Tensor loss = torch::nn::functional::cross_entropy(logits, y);
      loss.backward();
      optimizer.step();
      loss_sum += loss.item<double>() * static_cast<double>(end - begin);
      correct += logits.argmax(1).eq(y).sum().item<std::int64_t>();
      seen += end - begin;
    }
    EpochStats s;
    s.epoch = epoch;
    s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    s.images_per_second = static_cast<double>(n) / std::max(s.seconds, 1e-9);
    s.train_loss = loss_sum / static_cast<double>(seen);
    s.train_accuracy = static_cast<double>(correct) / static_cast<double>(seen);
    if (eval_set) {
      const EvalResult r = evaluate_tensors(m.net, held, params.classes, 256);
      s.has_eval = true;
      s.eval_loss = r.loss;
      s.eval_accuracy = r.accuracy;
      if (epoch == tp.epochs) result.eval = r;
    }
    result.epochs.push_back(s);
    if (on_epoch) on_epoch(s);
    else if (tp.progress) std::cout << format_epoch(s, tp.epochs) << std::endl;
  }
  m.net->eval();
  return result;
}

std::string format_epoch(const EpochStats& e, int epochs) {
  std::string line = fmt::format("epoch {:>3}/{}  train loss {:.4f} nats  train acc {:5.1f} %", e.epoch,
                                 epochs, e.train_loss, 100.0 * e.train_accuracy);
  if (e.has_eval)
    line += fmt::format("  held-out loss {:.4f} nats  held-out acc {:5.1f} %", e.eval_loss,
                        100.0 * e.eval_accuracy);
  line += fmt::format("  {:.2f} s  {:.0f} images/s", e.seconds, e.images_per_second);
  return line;
}

std::string format_evaluation(const EvalResult& r, const ClassifierParams& params) {
  std::string out = fmt::format("accuracy {:.2f} % ({} images, mean loss {:.4f} nats)\n",
                                100.0 * r.accuracy, r.count, r.loss);
  const int k = static_cast<int>(r.confusion.size());
  std::size_t name_w = 10;
  for (int c = 0; c < k; ++c) name_w = std::max(name_w, params.class_name(c).size());
  const std::size_t col_w = std::max<std::size_t>(name_w, 8);
  out += "confusion matrix (images; rows = true class, columns = predicted class)\n";
  out += fmt::format("{:<{}}", "true\\pred", name_w);
  for (int c = 0; c < k; ++c) out += fmt::format("  {:>{}}", params.class_name(c), col_w);
  out += fmt::format("  {:>8}\n", "recall");
  const std::vector<double> recall = r.recall();
  for (int t = 0; t < k; ++t) {
    out += fmt::format("{:<{}}", params.class_name(t), name_w);
    for (int p = 0; p < k; ++p)
      out += fmt::format("  {:>{}}", r.confusion[static_cast<std::size_t>(t)][static_cast<std::size_t>(p)], col_w);
    out += std::isnan(recall[static_cast<std::size_t>(t)])
               ? fmt::format("  {:>8}\n", "-")
               : fmt::format("  {:>6.1f} %\n", 100.0 * recall[static_cast<std::size_t>(t)]);
  }
  return out;
}

}  // namespace comorph::perception
