// `comorph classifier ...`: train and evaluate the depth scene classifier
// (src/perception, docs/perception.md).
//
//   comorph classifier train --data FILE [--eval-data FILE] --out DIR
//                            [--config configs/perception.yaml] [--epochs E] [--seed S]
//   comorph classifier eval --model DIR --data FILE [--config FILE] [--switch-trials N] [--seed S]
//   comorph classifier synthetic --out FILE [--count N] [--seed S]
//
// Extending: the simulation side adds `comorph classifier dataset ...` (depth
// images rendered and labelled by the simulator, written with
// perception::DatasetWriter) HERE, in add_classifier_subcommands() below, next
// to `synthetic`, so every classifier command lives in this one file.
#include <spdlog/spdlog.h>

#include <filesystem>
#include <fmt/format.h>
#include <iostream>
#include <optional>
#include <stdexcept>

#include "command_registry.hpp"
#include "perception/dataset.hpp"
#include "perception/perception_config.hpp"
#include "perception/scene_classifier.hpp"
#include "perception/switch_evaluation.hpp"
#include "perception/synthetic.hpp"
#include "perception/training.hpp"

namespace {

namespace fs = std::filesystem;
namespace perception = comorph::perception;

std::string describe(const perception::Dataset& d, const perception::ClassifierParams& p) {
  std::string s = fmt::format("{} images of {}x{} pixels:", d.size(), d.height, d.width);
  const auto counts = d.class_counts();
  for (std::size_t c = 0; c < counts.size(); ++c)
    s += fmt::format(" {} {}", counts[c], p.class_name(static_cast<int>(c)));
  return s;
}

struct TrainOptions {
  std::string data, eval_data, out, config;
  std::optional<int> epochs;
  std::optional<std::uint64_t> seed;
};

void run_train(const TrainOptions& o) {
  perception::PerceptionConfig cfg;
  if (!o.config.empty()) cfg = perception::load_perception_config(o.config);
  if (o.epochs) cfg.training.epochs = *o.epochs;
  if (o.seed) cfg.training.seed = *o.seed;
  for (const std::string& err : {cfg.classifier.validate(), cfg.training.validate()})
    if (!err.empty()) throw std::runtime_error(err);
  // Everything is checked before DIR is created, so bad input leaves no directory.
  if (fs::exists(fs::path(o.out) / "classifier.pt"))
    throw std::runtime_error(o.out + " already holds a classifier; choose another --out");
  const perception::Dataset data = perception::load_dataset(o.data);
  std::optional<perception::Dataset> eval;
  if (!o.eval_data.empty()) eval = perception::load_dataset(o.eval_data);
  if (data.height != data.width)
    throw std::runtime_error(o.data + ": images are " + std::to_string(data.height) + "x" +
                             std::to_string(data.width) + "; the classifier needs square images");
  if (o.config.empty()) {  // no preset: take the shape from the data
    cfg.classifier.image_size = data.height;
    if (data.classes != cfg.classifier.classes) {
      cfg.classifier.classes = data.classes;
      cfg.classifier.class_names.clear();
    }
  }
  std::cout << "training data: " << o.data << ": " << describe(data, cfg.classifier) << "\n";
  if (eval) std::cout << "held-out data: " << o.eval_data << ": " << describe(*eval, cfg.classifier) << "\n";
  else std::cout << "held-out data: " << cfg.training.eval_fraction * 100 << " % of the training file (seeded split)\n";
  std::cout << fmt::format(
      "classifier: ResNet-18, width {} channels, {}x{} pixels, {} classes, device {}; "
      "{} epochs, batch {} images, lr {}, seed {}, {} thread(s)\n",
      cfg.classifier.width, cfg.classifier.image_size, cfg.classifier.image_size,
      cfg.classifier.classes, cfg.classifier.device, cfg.training.epochs, cfg.training.batch_size,
      cfg.training.learning_rate, cfg.training.seed, cfg.training.threads);

  perception::TrainResult r = perception::train_classifier(
      data, cfg.classifier, cfg.training, eval ? &*eval : nullptr);
  r.model.save(o.out);
  if (r.eval.count > 0) {
    std::cout << "held-out evaluation (" << r.eval_count << " images)\n"
              << perception::format_evaluation(r.eval, cfg.classifier);
  }
  std::cout << "saved " << (fs::path(o.out) / "classifier.pt").string() << " and "
            << (fs::path(o.out) / "classifier.yaml").string() << "\n";
}

struct EvalOptions {
  std::string model, data, config;
  int switch_trials = 100;
  std::uint64_t seed = 1;
};

void run_eval(const EvalOptions& o) {
  perception::PerceptionConfig cfg;
  if (!o.config.empty()) cfg = perception::load_perception_config(o.config);
  perception::SceneClassifier::set_threads(1);
  perception::SceneClassifier model = perception::SceneClassifier::load(o.model);
  const perception::Dataset data = perception::load_dataset(o.data);
  std::cout << o.data << ": " << describe(data, model.params()) << "\n";
  const perception::EvalResult r = perception::evaluate_classifier(model, data);
  std::cout << perception::format_evaluation(r, model.params());
  if (o.switch_trials > 0) {
    perception::SwitchTrialParams t;
    t.trials = o.switch_trials;
    t.seed = o.seed;
    const auto& d = cfg.switch_detector;
    std::cout << fmt::format(
        "switch trials: {} episodes of {} control steps, one scene change each in [{}, {}), frames drawn "
        "from the file; detector every {} steps, last {} frames, > {:.0f} % agree\n",
        t.trials, t.steps, t.earliest_change, t.latest_change, d.interval, d.window, 100 * d.agreement);
    std::cout << perception::format_switch_report(perception::evaluate_switching(model, data, d, t));
  }
}

void add_classifier_subcommands(CLI::App& app) {
  auto* cls = app.add_subcommand("classifier", "train and evaluate the depth scene classifier");
  cls->require_subcommand(1);

  auto* train = cls->add_subcommand("train", "train the ResNet-18 scene classifier on a dataset file");
  static TrainOptions to;
  train->add_option("--data", to.data, "training dataset file")->required();
  train->add_option("--eval-data", to.eval_data,
                    "held-out dataset file (default: hold out training.eval_fraction of --data)");
  train->add_option("--out", to.out, "directory to write classifier.pt and classifier.yaml to")->required();
  train->add_option("--config", to.config, "perception preset (e.g. configs/perception.yaml)");
  train->add_option("--epochs", to.epochs, "passes over the training data (overrides the preset)")
      ->check(CLI::PositiveNumber);
  train->add_option("--seed", to.seed, "seed of weights, split and shuffling (overrides the preset)");
  train->callback([] { run_train(to); });

  auto* eval = cls->add_subcommand("eval", "print accuracy and the confusion matrix of a saved classifier");
  static EvalOptions eo;
  eval->add_option("--model", eo.model, "directory written by `classifier train`")->required();
  eval->add_option("--data", eo.data, "dataset file")->required();
  eval->add_option("--config", eo.config, "perception preset for the switch detector (default: built-in)");
  eval->add_option("--switch-trials", eo.switch_trials,
                   "episodes with one scene change to measure the switch delay on (0 = skip)")
      ->check(CLI::NonNegativeNumber);
  eval->add_option("--seed", eo.seed, "seed of the switch trials");
  eval->callback([] { run_eval(eo); });

  auto* synth = cls->add_subcommand(
      "synthetic", "write a synthetic 3-class depth dataset (stairs / obstacles / open) for trials");
  static perception::SyntheticParams sp;
  static std::string synth_out;
  synth->add_option("--out", synth_out, "dataset file to write")->required();
  synth->add_option("--count", sp.count, "number of images")->check(CLI::PositiveNumber);
  synth->add_option("--size", sp.image_size, "image side, pixels")->check(CLI::Range(8, 256));
  synth->add_option("--noise", sp.noise, "std of the depth noise, depth units")->check(CLI::Range(0.0, 1.0));
  synth->add_option("--seed", sp.seed, "seed of the images");
  synth->callback([] {
    const perception::Dataset d = perception::make_synthetic_dataset(sp);
    perception::save_dataset(synth_out, d);
    std::cout << "wrote " << synth_out << ": " << describe(d, perception::ClassifierParams{}) << "\n";
  });

  // `dataset` (simulator-rendered images) will be added here by the sim side.
}

comorph::cli::CommandRegistration registration{add_classifier_subcommands};

}  // namespace
