// Parameter validation and the YAML form of the perception parameters.
#include "perception/perception_config.hpp"

#include <set>
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

namespace {

[[noreturn]] void fail(const std::string& source, const std::string& key, const std::string& what) {
  throw std::runtime_error(source + ": '" + key + "': " + what);
}

void check_keys(const YAML::Node& node, const std::string& source, const std::string& section,
                const std::set<std::string>& allowed) {
  if (!node.IsMap()) fail(source, section, "expected a mapping");
  for (const auto& item : node) {
    const std::string key = item.first.as<std::string>();
    if (!allowed.count(key)) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      fail(source, section.empty() ? key : section + "." + key, "unknown key (expected one of: " + list + ")");
    }
  }
}

template <typename T>
void read(const YAML::Node& node, const char* key, const std::string& source,
          const std::string& section, T& out) {
  if (!node[key]) return;
  try {
    out = node[key].as<T>();
  } catch (const YAML::Exception&) {
    fail(source, section + "." + key, "bad value '" + YAML::Dump(node[key]) + "'");
  }
}

}  // namespace

PerceptionConfig perception_config_from_yaml(const YAML::Node& root, const std::string& source) {
  PerceptionConfig cfg;
  if (!root || root.IsNull()) return cfg;
  check_keys(root, source, "", {"classifier", "training", "switch_detector"});
  if (const YAML::Node n = root["classifier"]) {
    check_keys(n, source, "classifier", {"image_size", "classes", "class_names", "width", "device"});
    ClassifierParams& c = cfg.classifier;
    read(n, "image_size", source, "classifier", c.image_size);
    read(n, "classes", source, "classifier", c.classes);
    read(n, "class_names", source, "classifier", c.class_names);
    read(n, "width", source, "classifier", c.width);
    read(n, "device", source, "classifier", c.device);
  }
  if (const YAML::Node n = root["training"]) {
    check_keys(n, source, "training",
               {"epochs", "batch_size", "learning_rate", "cosine_schedule", "weight_decay", "eval_fraction", "seed",
                "threads", "progress"});
    TrainParams& t = cfg.training;
    read(n, "epochs", source, "training", t.epochs);
    read(n, "batch_size", source, "training", t.batch_size);
    read(n, "learning_rate", source, "training", t.learning_rate);
    read(n, "cosine_schedule", source, "training", t.cosine_schedule);
    read(n, "weight_decay", source, "training", t.weight_decay);
    read(n, "eval_fraction", source, "training", t.eval_fraction);
    read(n, "seed", source, "training", t.seed);
    read(n, "threads", source, "training", t.threads);
    read(n, "progress", source, "training", t.progress);
  }
  if (const YAML::Node n = root["switch_detector"]) {
    check_keys(n, source, "switch_detector", {"interval", "window", "agreement"});
    SwitchDetectorParams& s = cfg.switch_detector;
    read(n, "interval", source, "switch_detector", s.interval);
    read(n, "window", source, "switch_detector", s.window);
    read(n, "agreement", source, "switch_detector", s.agreement);
  }
  for (const std::string& err :
       {cfg.classifier.validate(), cfg.training.validate(), cfg.switch_detector.validate()})
    if (!err.empty()) throw std::runtime_error(source + ": " + err);
  return cfg;
}

PerceptionConfig load_perception_config(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw std::runtime_error(path + ": cannot open");
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(path + ": not valid YAML: " + e.msg + " (line " +
                             std::to_string(e.mark.line + 1) + ")");
  }
  return perception_config_from_yaml(root, path);
}

}  // namespace comorph::perception
