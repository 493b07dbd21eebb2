// Binds the fields of a parameter struct to YAML keys, so that every config
// loader of every layer rejects unknown keys, values of the wrong type and
// numbers out of range with the file name and the field (yaml-cpp parses).
//
//   YamlFields f("configs/sim/robot.yaml");
//   f.add("wheel_radius", &p.wheel_radius, 0.01, 1.0);  // number with a range
//   f.add("device", &p.device);                         // any yaml-cpp type
//   f.add("loss", &p.loss);                             // enum, by name (enum_names.hpp)
//   f.apply(root);  // or f.apply_text(text)
//
// Dotted names ("stair.w1") bind keys of nested mappings. Errors are
// std::runtime_error "<source>: field '<name>': <what>"; an unknown enum name
// is "'<value>' is not one of <name> | <name> ...".
#pragma once

#include <yaml-cpp/yaml.h>

#include "common/enum_names.hpp"
#include "common/file_io.hpp"  // read_text_file, quote_value

#include <functional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace comorph {

class YamlFields {
 public:
  explicit YamlFields(std::string source) : source_(std::move(source)) {}

  // A field of any type yaml-cpp converts (numbers, bool, strings, lists), or
  // an enum with a names table, given by name.
  template <typename T>
  void add(const std::string& name, T* value) {
    fields_.push_back({name, [this, value](const YAML::Node& node, const std::string& key) {
                         *value = convert<T>(node, key);
                       }});
  }
  // A number that must lie in [min, max].
  // (min and max take T's type: `add("x", &a_double, 0, 1)` works.)
  template <typename T, typename = std::enable_if_t<std::is_arithmetic_v<T>>>
  void add(const std::string& name, T* value, std::common_type_t<T> min, std::common_type_t<T> max) {
    fields_.push_back({name, [this, value, min, max](const YAML::Node& node, const std::string& key) {
                         const T v = convert<T>(node, key);
                         if (!(v >= min && v <= max)) {
                           std::ostringstream os;
                           os << "value " << v << " out of range [" << min << ", " << max << "]";
                           fail(key, os.str());
                         }
                         *value = v;
                       }});
  }

  // Applies a YAML mapping (null: nothing to apply). `prefix` names nested maps.
  void apply(const YAML::Node& map, const std::string& prefix = "") const;
  // Parses text first (syntax errors name the source and the line).
  void apply_text(const std::string& text) const;

  [[noreturn]] void fail(const std::string& field, const std::string& what) const {
    throw std::runtime_error(source_ + ": field '" + quote_value(field) + "': " + what);
  }
  const std::string& source() const { return source_; }

 private:
  template <typename T>
  T convert(const YAML::Node& node, const std::string& key) const {
    if constexpr (std::is_enum_v<T>) {
      T v{};
      if (!node.IsScalar() || !enum_from_name(node.Scalar(), v))
        fail(key, "'" + quote_value(node.IsScalar() ? node.Scalar() : YAML::Dump(node)) + "' is not one of " +
                      enum_name_list<T>());
      return v;
    } else {
      try {
        return node.as<T>();
      } catch (const YAML::Exception&) {
        fail(key, "bad value '" + quote_value(YAML::Dump(node)) + "'");
      }
    }
  }

  struct Field {
    std::string name;
    std::function<void(const YAML::Node&, const std::string&)> set;
  };
  std::string source_;
  std::vector<Field> fields_;
};

// Parses YAML text; errors name `source` (and the line of a syntax error). A
// key that appears twice in one mapping is an error (yaml-cpp would keep one
// of them without a word).
YAML::Node parse_yaml(const std::string& text, const std::string& source);
// parse_yaml of a file (read_text_file: size cap, not a directory).
YAML::Node load_yaml_file(const std::string& path);

}  // namespace comorph
