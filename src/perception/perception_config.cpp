// Parameter validation and the YAML form of the perception parameters.
#include "perception/perception_config.hpp"

#include "common/yaml_fields.hpp"

#include <stdexcept>

namespace comorph::perception {

std::string ClassifierParams::validate() const {
  if (image_size < 8 || image_size > 256)
    return "classifier.image_size must be in 8..256 pixels, got " + std::to_string(image_size);
  if (classes < 2 || classes > 255)
    return "classifier.classes must be in 2..255, got " + std::to_string(classes);
  if (width < 1 || width > 512) return "classifier.width must be in 1..512 channels, got " + std::to_string(width);
  if (!class_names.empty() && static_cast<int>(class_names.size()) != classes)
    return "classifier.class_names has " + std::to_string(class_names.size()) +
           " names for " + std::to_string(classes) + " classes";
  if (device.empty()) return "classifier.device is empty (cpu, cuda, cuda:N)";
  return "";
}

std::string ClassifierParams::class_name(int c) const {
  if (c >= 0 && c < static_cast<int>(class_names.size())) return class_names[static_cast<std::size_t>(c)];
  return "class " + std::to_string(c);
}

std::string TrainParams::validate() const {
  if (epochs < 1) return "training.epochs must be >= 1, got " + std::to_string(epochs);
  if (batch_size < 2) return "training.batch_size must be >= 2 (batch norm), got " + std::to_string(batch_size);
  if (!(learning_rate > 0)) return "training.learning_rate must be > 0";
  if (!(weight_decay >= 0)) return "training.weight_decay must be >= 0";
  if (!(eval_fraction >= 0 && eval_fraction < 1)) return "training.eval_fraction must be in [0, 1)";
  if (threads < 1) return "training.threads must be >= 1, got " + std::to_string(threads);
  return "";
}

void add_fields(YamlFields& f, PerceptionConfig& cfg) {
  ClassifierParams& c = cfg.classifier;
  TrainParams& t = cfg.training;
  SwitchDetectorParams& d = cfg.switch_detector;
  // Ranges and cross-field rules live in the structs' validate() (also for
  // parameters set in code); here: keys, types and meanings.
  f.add("classifier.image_size", &c.image_size, "pixels, side of the square depth image classified (8..256)");
  f.add("classifier.classes", &c.classes, "scene classes (2..255)");
  f.add("classifier.class_names", &c.class_names, "a name per class (empty: class 0, class 1, ...)");
  f.add("classifier.width", &c.width, "channels of the ResNet's first stage (1..512; the standard ResNet-18: 64)");
  f.add("classifier.device", &c.device, "torch device (cpu, cuda, cuda:N)");
  f.add("training.epochs", &t.epochs, "passes over the training set (>= 1)");
  f.add("training.batch_size", &t.batch_size, "images per Adam step (>= 2, batch norm)");
  f.add("training.learning_rate", &t.learning_rate, "Adam step size at the start (> 0)");
  f.add("training.cosine_schedule", &t.cosine_schedule, "cosine decay of the step size to 0 over all batches");
  f.add("training.weight_decay", &t.weight_decay, "L2 penalty of Adam (>= 0)");
  f.add("training.eval_fraction", &t.eval_fraction, "fraction held out for evaluation without an evaluation set, [0, 1)");
  f.add("training.seed", &t.seed, "seed of weight init, split and minibatch shuffling");
  f.add("training.threads", &t.threads, "torch intra-op threads (>= 1)");
  f.add("training.progress", &t.progress, "print one line per epoch");
  f.add("switch_detector.interval", &d.interval, "control steps between two switch decisions (paper: 100)");
  f.add("switch_detector.window", &d.window, "frame labels looked at per decision (paper: 10)");
  f.add("switch_detector.agreement", &d.agreement,
        "fraction of the window that must agree, strictly exceeded (paper: 0.7), [0, 1)");
}

PerceptionConfig perception_config_from_yaml(const YAML::Node& root, const std::string& source) {
  PerceptionConfig cfg;
  YamlFields f(source);
  add_fields(f, cfg);
  f.apply(root);
  const ClassifierParams& c = cfg.classifier;
  const TrainParams& t = cfg.training;
  const SwitchDetectorParams& d = cfg.switch_detector;
  for (const std::string& err : {c.validate(), t.validate(), d.validate()})
    if (!err.empty()) throw std::runtime_error(source + ": " + err);
  return cfg;
}

PerceptionConfig load_perception_config(const std::string& path) {
  return perception_config_from_yaml(load_yaml_file(path), path);
}

}  // namespace comorph::perception
