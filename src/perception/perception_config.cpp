// Parameter validation and the YAML form of the perception parameters.
#include "perception/perception_config.hpp"

#include "common/yaml_fields.hpp"

#include <stdexcept>

namespace comorph::perception {

std::string ClassifierParams::validate() const {
  PerceptionConfig config;
  config.classifier = *this;
  if (std::string fault = range_fault(config); !fault.empty()) return fault;
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
  PerceptionConfig config;
  config.training = *this;
  return range_fault(config);
}

void add_fields(YamlFields& f, PerceptionConfig& cfg) {
  ClassifierParams& c = cfg.classifier;
  TrainParams& t = cfg.training;
  SwitchDetectorParams& d = cfg.switch_detector;
  // Each range is declared here once; the structs' validate() checks values
  // set in code against it (range_fault) and adds the rules between fields.
  f.add("classifier.image_size", &c.image_size, 8, 256, "pixels, side of the square depth image classified");
  f.add("classifier.classes", &c.classes, 2, 255, "scene classes");
  f.add("classifier.class_names", &c.class_names, "a name per class (empty: class 0, class 1, ...)");
  f.add("classifier.width", &c.width, 1, 512, "channels of the ResNet's first stage (the standard ResNet-18: 64)");
  f.add("classifier.device", &c.device, "torch device (cpu, cuda, cuda:N)");
  f.add("training.epochs", &t.epochs, 1, 1000000, "passes over the training set");
  f.add("training.batch_size", &t.batch_size, 2, 1000000, "images per Adam step (2 at least: batch norm)");
  f.add("training.learning_rate", &t.learning_rate, 1e-12, 10, "Adam step size at the start");
  f.add("training.cosine_schedule", &t.cosine_schedule, "cosine decay of the step size to 0 over all batches");
  f.add("training.weight_decay", &t.weight_decay, 0, 10, "L2 penalty of Adam");
  f.add("training.eval_fraction", &t.eval_fraction, 0, 0.99,
        "fraction held out for evaluation without an evaluation set");
  f.add("training.seed", &t.seed, "seed of weight init, split and minibatch shuffling");
  f.add("training.threads", &t.threads, 1, 1024, "torch intra-op threads");
  f.add("training.progress", &t.progress, "print one line per epoch");
  f.add("switch_detector.interval", &d.interval, 1, 1000000, "control steps between two switch decisions (paper: 100)");
  f.add("switch_detector.window", &d.window, 1, 100000, "frame labels looked at per decision (paper: 10)");
  f.add("switch_detector.agreement", &d.agreement, 0, 1,
        "fraction of the window that must agree, strictly exceeded, below 1 (paper: 0.7)");
}

std::string range_fault(const PerceptionConfig& config) {
  PerceptionConfig copy = config;
  YamlFields f("perception");
  add_fields(f, copy);
  try {
    f.apply(f.values());  // YamlFields checks every range as it reads
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
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
