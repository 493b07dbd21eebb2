// `comorph classifier ...`: train and evaluate the depth scene classifier
// (src/perception, docs/perception.md).
//
//   comorph classifier train --data FILE [--eval-data FILE] --out DIR
//                            [--config configs/perception.yaml] [--epochs E] [--seed S]
//   comorph classifier eval --model DIR --data FILE [--config FILE] [--switch-trials N] [--seed S]
//   comorph classifier synthetic --out FILE [--count N] [--seed S]
//   comorph classifier dataset --out FILE [--seeds A:B] [--frames-per-seed N] [--seed S]
//                              [--config-dir configs/sim]
//   comorph classifier prepare --out DIR [--config configs/perception.yaml] [--train-seeds A:B]
//                              [--eval-seeds C:D] [--epochs E] [--frames-per-seed N] [--seed S]
//                              [--config-dir configs/sim]
//
// `dataset` and `prepare` take their images from the simulator
// (perception_sim/scene_dataset.hpp: scripted-pilot runs and level views of seeded
// scenes, labelled from ground truth); docs/perception.md, "Data from the
// simulator".
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "cli_numbers.hpp"
#include "common/file_io.hpp"
#include "common/resources.hpp"
#include "command_registry.hpp"
#include "perception_sim/scene_dataset.hpp"
#include "perception/dataset.hpp"
#include "perception/perception_config.hpp"
#include "perception/scene_classifier.hpp"
#include "perception/switch_evaluation.hpp"
#include "perception/synthetic.hpp"
#include "perception/training.hpp"
#include "task/env_config.hpp"

namespace {

namespace fs = std::filesystem;
namespace perception = comorph::perception;
namespace cli = comorph::cli;

constexpr long long kMaxSeed = 1LL << 53;  // seeds every seed type here holds exactly

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

// ---- data from the simulator: `dataset` and `prepare` ----

namespace perception_sim = comorph::perception_sim;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// One stderr line about every tenth of the seeds (and the last).
perception_sim::SeedProgress seed_progress(const std::string& what) {
  return [what](int done, int total, const perception_sim::SceneDatasetStats& st) {
    const int every = std::max(1, total / 10);
    if (done % every == 0 || done == total)
      std::cerr << fmt::format("{}: seed {}/{}, {} images, {} control steps simulated, {:.1f} s\n", what, done,
                               total, st.images(), st.run_steps, st.seconds);
  };
}

struct DatasetOptions {
  std::string out, seeds = "1:30", config_dir;  // "": configs/sim of resource_dir()
  int frames_per_seed = perception_sim::SceneDatasetParams{}.frames_per_seed;
  double run_fraction = perception_sim::SceneDatasetParams{}.run_fraction;
  std::uint64_t seed = 1;
};

void run_dataset(const DatasetOptions& o) {
  perception_sim::SceneDatasetParams p;
  perception_sim::parse_seed_range(o.seeds, "--seeds", p.first_seed, p.last_seed);
  p.frames_per_seed = o.frames_per_seed;
  p.run_fraction = o.run_fraction;
  p.seed = o.seed;
  if (const std::string err = p.validate(); !err.empty()) throw std::runtime_error(err);
  const comorph::task::EnvConfig env =
      comorph::task::load_env_config(comorph::given_or_resource(o.config_dir, "configs/sim"));
  std::cerr << fmt::format("dataset: scene seeds {}..{} ({} seeds), {} images a seed ({:.0f} % from scripted runs), "
                           "{}x{} pixels, generator seed {}\n",
                           p.first_seed, p.last_seed, p.seeds(), p.frames_per_seed, 100 * p.run_fraction,
                           env.robot.depth_height, env.robot.depth_width, p.seed);
  const perception_sim::SceneDatasetStats st = perception_sim::write_scene_dataset(o.out, env, p, seed_progress("dataset"));
  std::cout << "wrote " << o.out << ": " << perception_sim::format_class_balance(st) << "\n";
  std::cout << fmt::format("{}; {} control steps simulated; {:.1f} s\n", perception_sim::format_run_ends(st), st.run_steps,
                           st.seconds);
}

struct PrepareOptions {
  std::string out, config, config_dir;  // "": configs/perception.yaml, configs/sim of resource_dir()
  std::string train_seeds = "1:30", eval_seeds = "1001:1010";
  // Held-out accuracy on this data plateaus after 2-3 epochs: 6 (not the
  // preset's 10) keeps `prepare` at ~1.5 min on an idle 2-core machine.
  int epochs = 6;
  int frames_per_seed = perception_sim::SceneDatasetParams{}.frames_per_seed;
  double run_fraction = perception_sim::SceneDatasetParams{}.run_fraction;
  std::uint64_t seed = 1;
};

std::string json_number(double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : "null"; }

std::string json_delays(const perception::SwitchDelayReport& d, double max) {
  return fmt::format(
      "{{\"mean_delay_steps\": {}, \"max_delay_steps\": {}, \"detected\": {}, \"missed\": {}, "
      "\"false_switches\": {}}}",
      json_number(d.mean_delay()), json_number(max), d.detected, d.missed, d.false_switches);
}


void run_prepare(PrepareOptions o) {
  o.config = comorph::given_or_resource(o.config, "configs/perception.yaml");
  o.config_dir = comorph::given_or_resource(o.config_dir, "configs/sim");
  const auto t_start = std::chrono::steady_clock::now();
  // ---- everything is checked before anything is written ----
  perception::PerceptionConfig cfg = perception::load_perception_config(o.config);
  cfg.training.epochs = o.epochs;
  for (const std::string& err : {cfg.classifier.validate(), cfg.training.validate(), cfg.switch_detector.validate()})
    if (!err.empty()) throw std::runtime_error(o.config + ": " + err);
  const comorph::task::EnvConfig env = comorph::task::load_env_config(o.config_dir);
  if (cfg.classifier.image_size != env.robot.depth_width || cfg.classifier.image_size != env.robot.depth_height)
    throw std::runtime_error(fmt::format(
        "{}: classifier.image_size {} does not match the camera of {}/robot.yaml ({}x{} pixels)", o.config,
        cfg.classifier.image_size, o.config_dir, env.robot.depth_height, env.robot.depth_width));
  if (cfg.classifier.classes != 3)
    throw std::runtime_error(fmt::format("{}: classifier.classes {}: the simulator labels 3 scene classes",
                                         o.config, cfg.classifier.classes));
  perception_sim::SceneDatasetParams train_p, eval_p;
  perception_sim::parse_seed_range(o.train_seeds, "--train-seeds", train_p.first_seed, train_p.last_seed);
  perception_sim::parse_seed_range(o.eval_seeds, "--eval-seeds", eval_p.first_seed, eval_p.last_seed);
  if (!(train_p.last_seed < eval_p.first_seed || eval_p.last_seed < train_p.first_seed))
    throw std::runtime_error(fmt::format("--train-seeds {} and --eval-seeds {} overlap: held-out seeds must be disjoint",
                                         o.train_seeds, o.eval_seeds));
  train_p.frames_per_seed = eval_p.frames_per_seed = o.frames_per_seed;
  train_p.run_fraction = eval_p.run_fraction = o.run_fraction;
  train_p.seed = eval_p.seed = o.seed;
  for (const std::string& err : {train_p.validate(), eval_p.validate()})
    if (!err.empty()) throw std::runtime_error(err);
  perception_sim::EpisodeSwitchParams episodes;
  episodes.first_seed = eval_p.first_seed;
  episodes.last_seed = eval_p.last_seed;
  episodes.seed = o.seed;
  const fs::path out(o.out);
  if (fs::exists(out) && !(fs::is_directory(out) && fs::is_empty(out)))
    throw std::runtime_error(o.out + " exists and is not an empty directory; choose another --out");
  // Everything goes to DIR.partial, renamed to DIR at the end: an error leaves no DIR.
  const fs::path stage = out.string() + ".partial";
  fs::remove_all(stage);
  fs::create_directories(stage);
  try {
    std::ostringstream report;  // also written to DIR/classifier-eval.txt
    auto say = [&](const std::string& text) {
      std::cout << text << std::flush;
      report << text;
    };
    say(fmt::format("classifier prepare: train seeds {}..{}, held-out seeds {}..{}, {} images a seed, "
                    "generator seed {}\n",
                    train_p.first_seed, train_p.last_seed, eval_p.first_seed, eval_p.last_seed,
                    train_p.frames_per_seed, o.seed));

    // ---- data ----
    const perception_sim::SceneDataset train = perception_sim::make_scene_dataset(env, train_p, seed_progress("training data"));
    const perception_sim::SceneDataset eval = perception_sim::make_scene_dataset(env, eval_p, seed_progress("held-out data"));
    perception::save_dataset((stage / "train.bin").string(), train.data);
    perception::save_dataset((stage / "eval.bin").string(), eval.data);
    say(fmt::format("training data (train.bin): {}; {:.1f} s\n", perception_sim::format_class_balance(train.stats),
                    train.stats.seconds));
    say(fmt::format("held-out data (eval.bin): {}; {:.1f} s\n", perception_sim::format_class_balance(eval.stats),
                    eval.stats.seconds));

    // ---- training ----
    say(fmt::format("classifier: ResNet-18, width {} channels, {}x{} pixels, {} classes; {} epochs, batch {} images, "
                    "lr {}, seed {}, {} thread(s)\n",
                    cfg.classifier.width, cfg.classifier.image_size, cfg.classifier.image_size,
                    cfg.classifier.classes, cfg.training.epochs, cfg.training.batch_size,
                    cfg.training.learning_rate, cfg.training.seed, cfg.training.threads));
    const auto t_train = std::chrono::steady_clock::now();
    perception::TrainResult r = perception::train_classifier(train.data, cfg.classifier, cfg.training, &eval.data);
    const double train_seconds = seconds_since(t_train);
    if (!r.epochs.empty()) report << perception::format_epoch(r.epochs.back(), cfg.training.epochs) << "\n";
    say(fmt::format("training: {:.1f} s\n", train_seconds));

    // ---- held-out accuracy: all, and per source ----
    say(fmt::format("held-out evaluation (seeds {}..{}, never trained on)\n", eval_p.first_seed, eval_p.last_seed));
    say(perception::format_evaluation(r.eval, cfg.classifier));
    double source_accuracy[2] = {NAN, NAN};
    std::size_t source_count[2] = {0, 0};
    for (const perception_sim::FrameSource src : {perception_sim::FrameSource::run, perception_sim::FrameSource::view}) {
      std::vector<std::size_t> idx;
      for (std::size_t i = 0; i < eval.info.size(); ++i)
        if (eval.info[i].source == src) idx.push_back(i);
      if (idx.empty()) continue;
      const perception::EvalResult e = perception::evaluate_classifier(r.model, eval.data.subset(idx));
      const int k = static_cast<int>(src);
      source_accuracy[k] = e.accuracy;
      source_count[k] = e.count;
      say(fmt::format("  {} frames: accuracy {:.2f} % ({} images)\n",
                      src == perception_sim::FrameSource::run ? "scripted-run" : "level-view", 100 * e.accuracy, e.count));
    }

    // ---- switch delay in real episodes on the held-out seeds ----
    perception::SceneClassifier::set_threads(1);
    const perception_sim::EpisodeSwitchReport sw = perception_sim::evaluate_switching_in_episodes(
        env, r.model, cfg.switch_detector, episodes, [](int done, int total) {
          std::cerr << fmt::format("switch episodes: {}/{}\n", done, total);
        });
    const auto& d = cfg.switch_detector;
    say(fmt::format("switch detector: every {} control steps, last {} frames, > {:.0f} % agree\n", d.interval,
                    d.window, 100 * d.agreement));
    say(perception_sim::format_episode_switch_report(sw));
    say(fmt::format("  ({:.1f} s)\n", sw.seconds));

    // ---- save ----
    r.model.save(stage.string());
    const double total_seconds = seconds_since(t_start);
    say(fmt::format("wall time: data {:.1f} s, training {:.1f} s, switch episodes {:.1f} s, total {:.1f} s\n",
                    train.stats.seconds + eval.stats.seconds, train_seconds, sw.seconds, total_seconds));
    comorph::write_file_atomic((stage / "classifier-eval.txt").string(), report.str());
    std::string confusion = "[";
    for (std::size_t t = 0; t < r.eval.confusion.size(); ++t) {
      confusion += t ? ", [" : "[";
      for (std::size_t p = 0; p < r.eval.confusion[t].size(); ++p)
        confusion += (p ? ", " : "") + std::to_string(r.eval.confusion[t][p]);
      confusion += "]";
    }
    confusion += "]";
    comorph::write_file_atomic(
        (stage / "classifier-eval.json").string(),
        fmt::format("{{\n  \"train_seeds\": [{}, {}],\n  \"eval_seeds\": [{}, {}],\n  \"train_images\": {},\n"
                    "  \"eval_images\": {},\n  \"width\": {},\n  \"epochs\": {},\n  \"eval_accuracy\": {},\n"
                    "  \"eval_accuracy_run_frames\": {},\n  \"eval_accuracy_view_frames\": {},\n"
                    "  \"eval_run_frames\": {},\n  \"eval_view_frames\": {},\n"
                    "  \"confusion\": {},\n  \"confusion_layout\": \"rows = true class, columns = predicted; "
                    "stairs, obstacle_field, target_zone\",\n"
                    "  \"switch_episodes\": {},\n  \"switch_initial_wrong\": {},\n  \"switch\": {},\n"
                    "  \"switch_rule_only\": {},\n  \"data_seconds\": {},\n  \"train_seconds\": {},\n"
                    "  \"switch_seconds\": {},\n  \"total_seconds\": {}\n}}\n",
                    train_p.first_seed, train_p.last_seed, eval_p.first_seed, eval_p.last_seed, train.data.size(),
                    eval.data.size(), cfg.classifier.width, cfg.training.epochs, json_number(r.eval.accuracy),
                    json_number(source_accuracy[0]), json_number(source_accuracy[1]), source_count[0],
                    source_count[1], confusion, sw.episodes, sw.initial_wrong,
                    json_delays(sw.monitor, sw.monitor_max_delay), json_delays(sw.rule_only, sw.rule_only_max_delay),
                    json_number(train.stats.seconds + eval.stats.seconds), json_number(train_seconds),
                    json_number(sw.seconds), json_number(total_seconds)));
    if (fs::exists(out)) fs::remove(out);  // an empty directory (checked above)
    fs::rename(stage, out);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(stage, ec);
    throw;
  }
  std::cout << fmt::format("saved {0}/classifier.pt, classifier.yaml, classifier-eval.txt, classifier-eval.json, "
                           "train.bin, eval.bin\nuse it: scene_source: classifier, classifier_dir: {0}\n",
                           o.out);
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
      ->check(cli::whole_in(1, 100000));
  train->add_option("--seed", to.seed, "seed of weights, split and shuffling (overrides the preset)")
      ->check(cli::whole_in(0, kMaxSeed));
  train->callback([] { run_train(to); });

  auto* eval = cls->add_subcommand("eval", "print accuracy and the confusion matrix of a saved classifier");
  static EvalOptions eo;
  eval->add_option("--model", eo.model, "directory written by `classifier train`")->required();
  eval->add_option("--data", eo.data, "dataset file")->required();
  eval->add_option("--config", eo.config, "perception preset for the switch detector (default: built-in)");
  eval->add_option("--switch-trials", eo.switch_trials,
                   "episodes with one scene change to measure the switch delay on (0 = skip)")
      ->check(cli::whole_in(0, 1000000));
  eval->add_option("--seed", eo.seed, "seed of the switch trials")->check(cli::whole_in(0, kMaxSeed));
  eval->callback([] { run_eval(eo); });

  auto* synth = cls->add_subcommand(
      "synthetic", "write a synthetic 3-class depth dataset (stairs / obstacles / open) for trials");
  static perception::SyntheticParams sp;
  static std::string synth_out;
  synth->add_option("--out", synth_out, "dataset file to write")->required();
  synth->add_option("--count", sp.count, "number of images")->check(cli::whole_in(1, 10000000));
  synth->add_option("--size", sp.image_size, "image side, pixels")->check(cli::whole_in(8, 256));
  synth->add_option("--noise", sp.noise, "std of the depth noise, depth units")->check(cli::finite_in(0.0, 1.0));
  synth->add_option("--seed", sp.seed, "seed of the images")->check(cli::whole_in(0, kMaxSeed));
  synth->callback([] {
    const perception::Dataset d = perception::make_synthetic_dataset(sp);
    perception::save_dataset(synth_out, d);
    std::cout << "wrote " << synth_out << ": " << describe(d, perception::ClassifierParams{}) << "\n";
  });

  auto* data = cls->add_subcommand(
      "dataset", "write a depth dataset rendered by the simulator and labelled from ground truth");
  static DatasetOptions dop;
  data->add_option("--out", dop.out, "dataset file to write")->required();
  data->add_option("--seeds", dop.seeds, "scene seeds A:B, inclusive (held-out sets: a disjoint range)");
  data->add_option("--frames-per-seed", dop.frames_per_seed, "images per scene seed")
      ->check(cli::whole_in(1, 100000));
  data->add_option("--run-fraction", dop.run_fraction,
                   "share of a seed's images from its scripted run (the rest: level views), 0..1")
      ->check(cli::finite_in(0.0, 1.0));
  data->add_option("--seed", dop.seed, "generator seed (chain lengths, obstacle counts, frame picks, view poses)")
      ->check(cli::whole_in(0, kMaxSeed));
  data->add_option("--config-dir", dop.config_dir, cli::kConfigDirHelp);
  data->callback([] { run_dataset(dop); });

  auto* prep = cls->add_subcommand(
      "prepare", "simulator data (train + held-out seeds), training, held-out accuracy and switch delays in "
                 "scripted episodes; saves everything to --out");
  static PrepareOptions po;
  prep->add_option("--out", po.out, "directory to create (must not exist or be empty)")->required();
  prep->add_option("--config", po.config, "perception preset (default: configs/perception.yaml of comorph's data files)");
  prep->add_option("--train-seeds", po.train_seeds, "scene seeds A:B (inclusive) of the training data");
  prep->add_option("--eval-seeds", po.eval_seeds,
                   "scene seeds C:D (inclusive, disjoint from the training seeds) of the held-out data and the "
                   "switch-delay episodes");
  prep->add_option("--epochs", po.epochs,
                   "passes over the training data (default 6, not the preset's: held-out accuracy plateaus after 2-3)")
      ->check(cli::whole_in(1, 100000));
  prep->add_option("--frames-per-seed", po.frames_per_seed, "images per scene seed")->check(cli::whole_in(1, 100000));
  prep->add_option("--run-fraction", po.run_fraction,
                   "share of a seed's images from its scripted run (the rest: level views), 0..1")
      ->check(cli::finite_in(0.0, 1.0));
  prep->add_option("--seed", po.seed, "generator seed of the data and the episodes")->check(cli::whole_in(0, kMaxSeed));
  prep->add_option("--config-dir", po.config_dir, cli::kConfigDirHelp);
  prep->callback([] { run_prepare(po); });
}

comorph::cli::CommandRegistration registration{add_classifier_subcommands};

}  // namespace
