// Binds the fields of a parameter struct to YAML keys, each declared once with
// its meaning (and, for a number, its range), so that one list serves every
// use of a config: reading it (unknown keys, values of the wrong type and
// numbers out of range are refused with the file, the field and the line),
// listing it (`comorph config keys`, docs/config.md) and writing the values
// back (a run's resolved config.yaml).
//
//   YamlFields f("configs/sim/robot.yaml");
//   f.add("wheel_radius", &p.wheel_radius, 0.01, 1.0, "m, wheel radius");  // number with a range
//   f.add("device", &p.device, "torch device of the networks");             // any yaml-cpp type
//   f.add("loss", &p.loss, "loss on the TD error");                        // enum, by name (enum_names.hpp)
//   f.apply(root);  // or f.apply_text(text)
//   f.values();     // the bound values as YAML; f.settings(): what `config keys` lists
//
// Dotted names ("stair.w1") bind keys of nested mappings. Errors are
// std::runtime_error "<source>: field '<name>': <what> (line <n>)"; an
// unknown enum name is "'<value>' is not one of <name> | <name> ...".
#pragma once

#include <yaml-cpp/yaml.h>

#include "common/enum_names.hpp"
#include "common/file_io.hpp"  // read_text_file, quote_value

#include <charconv>
#include <functional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace comorph {

// One field as `comorph config keys` and docs/config.md list it.
struct Setting {
  std::string key;      // dotted name
  std::string type;     // "number", "integer", "bool", "text", "list of integer", or "a | b" for an enum
  std::string range;    // "[min, max]", or "" when any value of the type is accepted
  std::string value;    // the bound value, as YAML (the default when listed from a default struct)
  std::string meaning;  // one line
};

// The shortest text that reads back as the same number ("0.0003", "1e-12", "4000").
template <typename T>
std::string number_text(T value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

namespace yaml_fields_detail {
template <typename T>
struct is_vector : std::false_type {};
template <typename T>
struct is_vector<std::vector<T>> : std::true_type {};

template <typename T>
std::string type_name() {
  if constexpr (std::is_enum_v<T>) return enum_name_list<T>();
  else if constexpr (std::is_same_v<T, bool>) return "bool";
  else if constexpr (std::is_floating_point_v<T>) return "number";
  else if constexpr (std::is_integral_v<T>) return "integer";
  else if constexpr (std::is_same_v<T, std::string>) return "text";
  else if constexpr (is_vector<T>::value) return "list of " + type_name<typename T::value_type>();
  else static_assert(sizeof(T) == 0, "YamlFields: no type name for this field type");
}

template <typename T>
YAML::Node to_node(const T& v) {
  if constexpr (std::is_enum_v<T>) return YAML::Node(name_of(v));
  else if constexpr (std::is_same_v<T, bool>) return YAML::Node(v ? "true" : "false");
  else if constexpr (std::is_arithmetic_v<T>) return YAML::Node(number_text(v));
  else if constexpr (is_vector<T>::value) {
    YAML::Node list(YAML::NodeType::Sequence);
    for (const auto& item : v) list.push_back(to_node(item));
    list.SetStyle(YAML::EmitterStyle::Flow);
    return list;
  } else {
    return YAML::Node(v);
  }
}
}  // namespace yaml_fields_detail

class YamlFields {
 public:
  explicit YamlFields(std::string source) : source_(std::move(source)) {}

  // Names added from now on start with `prefix` ("env.robot."): one list can
  // hold the fields of several structs, each under its section.
  void set_prefix(std::string prefix) { prefix_ = std::move(prefix); }

  // A field of any type yaml-cpp converts (numbers, bool, strings, lists), or
  // an enum with a names table, given by name. `meaning`: one line, with the unit.
  template <typename T>
  void add(const std::string& name, T* value, std::string meaning) {
    fields_.push_back({prefix_ + name,
                       [this, value](const YAML::Node& node, const std::string& key) {
                         *value = convert<T>(node, key);
                       },
                       [value] { return yaml_fields_detail::to_node(*value); },
                       yaml_fields_detail::type_name<T>(), "", std::move(meaning)});
  }
  // A number that must lie in [min, max].
  // (min and max take T's type: `add("x", &a_double, 0, 1, "...")` works.)
  template <typename T, typename = std::enable_if_t<std::is_arithmetic_v<T>>>
  void add(const std::string& name, T* value, std::common_type_t<T> min, std::common_type_t<T> max,
           std::string meaning) {
    fields_.push_back({prefix_ + name,
                       [this, value, min, max](const YAML::Node& node, const std::string& key) {
                         const T v = convert<T>(node, key);
                         if (!(v >= min && v <= max)) {
                           std::ostringstream os;
                           os << "value " << v << " out of range [" << min << ", " << max << "]";
                           fail(key, os.str(), node);
                         }
                         *value = v;
                       },
                       [value] { return yaml_fields_detail::to_node(*value); },
                       yaml_fields_detail::type_name<T>(), "[" + number_text(min) + ", " + number_text(max) + "]",
                       std::move(meaning)});
  }

  // Applies a YAML mapping (null: nothing to apply). `prefix` names nested maps.
  void apply(const YAML::Node& map, const std::string& prefix = "") const;
  // Parses text first (syntax errors name the source and the line).
  void apply_text(const std::string& text) const;

  // The bound values as a YAML mapping, dotted names as nested mappings, in
  // the order of the add() calls.
  YAML::Node values() const;
  // Every field with its type, range, bound value and meaning, in that order.
  std::vector<Setting> settings() const;

  [[noreturn]] void fail(const std::string& field, const std::string& what) const {
    throw std::runtime_error(source_ + ": field '" + quote_value(field) + "': " + what);
  }
  // The same, with the line of `node` in the source when it has one.
  [[noreturn]] void fail(const std::string& field, const std::string& what, const YAML::Node& node) const;
  const std::string& source() const { return source_; }

 private:
  template <typename T>
  T convert(const YAML::Node& node, const std::string& key) const {
    if constexpr (std::is_enum_v<T>) {
      T v{};
      if (!node.IsScalar() || !enum_from_name(node.Scalar(), v))
        fail(key,
             "'" + quote_value(node.IsScalar() ? node.Scalar() : YAML::Dump(node)) + "' is not one of " +
                 enum_name_list<T>(),
             node);
      return v;
    } else {
      try {
        return node.as<T>();
      } catch (const YAML::Exception&) {
        fail(key, "bad value '" + quote_value(YAML::Dump(node)) + "', expected " + yaml_fields_detail::type_name<T>(),
             node);
      }
    }
  }

  struct Field {
    std::string name;
    std::function<void(const YAML::Node&, const std::string&)> set;
    std::function<YAML::Node()> get;
    std::string type, range, meaning;
  };
  std::string source_;
  std::string prefix_;
  std::vector<Field> fields_;
};

// Parses YAML text; errors name `source` (and the line of a syntax error). A
// key that appears twice in one mapping, or a key that is a list or a mapping
// instead of a name, is an error (yaml-cpp would keep one of the twins
// without a word, and fail on the other without naming the file).
YAML::Node parse_yaml(const std::string& text, const std::string& source);
// parse_yaml of a file (read_text_file: size cap, not a directory).
YAML::Node load_yaml_file(const std::string& path);
// " (line N)" for a node read from text; "" for one built in code.
std::string line_of(const YAML::Node& node);

}  // namespace comorph
