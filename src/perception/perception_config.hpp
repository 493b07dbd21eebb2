// The perception section of a preset (configs/perception.yaml): classifier
// architecture, its training, and the switch detector. Unknown keys and
// out-of-range values throw std::runtime_error naming the source and the key.
//
//   classifier:      {image_size, classes, class_names, width, device}
//   training:        {epochs, batch_size, learning_rate, cosine_schedule, weight_decay,
//                     eval_fraction, seed, threads, progress}
//   switch_detector: {interval, window, agreement}
// Every key is optional; a missing key keeps the default of params.hpp /
// switch_detector.hpp.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

#include "perception/params.hpp"
#include "perception/switch_detector.hpp"

namespace comorph {
class YamlFields;
}

namespace comorph::perception {

struct PerceptionConfig {
  ClassifierParams classifier;
  TrainParams training;
  SwitchDetectorParams switch_detector;
};

// Every field of PerceptionConfig with its range and meaning.
void add_fields(YamlFields& f, PerceptionConfig& config);
// The first value of `config` outside its range in add_fields, as an error
// ("perception: field '<key>': value <v> out of range [min, max]"), or "".
// The structs' validate() use it for values set in code.
std::string range_fault(const PerceptionConfig& config);
PerceptionConfig load_perception_config(const std::string& path);
// `node` is the mapping above (e.g. the `perception:` section of a preset).
PerceptionConfig perception_config_from_yaml(const YAML::Node& node, const std::string& source);

}  // namespace comorph::perception
