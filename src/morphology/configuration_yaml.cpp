// YAML form of a configuration. Every error names the source and the field.
#include <yaml-cpp/yaml.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

#include "common/yaml_fields.hpp"  // parse_yaml, read_text_file, write_file_atomic
#include "morphology/configuration.hpp"

namespace comorph {
namespace {

[[noreturn]] void fail(const std::string& source, const std::string& field,
                       const std::string& what) {
  throw std::runtime_error(source + ": field '" + field + "': " + what);
}

int read_int(const YAML::Node& node, const std::string& source, const std::string& field) {
  if (!node.IsScalar()) fail(source, field, "expected an integer");
  try {
    return node.as<int>();
  } catch (const YAML::Exception&) {
    fail(source, field, "'" + node.Scalar() + "' is not an integer");
  }
}

template <std::size_t Rows, std::size_t Cols>
void read_matrix(const YAML::Node& node, const std::string& source, const std::string& name,
                 std::size_t required_rows, std::array<std::array<int, Cols>, Rows>& out) {
  if (!node.IsSequence()) fail(source, name, "expected a list of rows");
  if (node.size() > Rows || node.size() < required_rows)
    fail(source, name,
         "has " + std::to_string(node.size()) + " rows, expected " +
             (required_rows == Rows ? std::to_string(Rows) : "at most " + std::to_string(Rows)));
  for (std::size_t r = 0; r < node.size(); ++r) {
    const std::string row_field = name + "[" + std::to_string(r) + "]";
    const YAML::Node row = node[r];
    if (!row.IsSequence() || row.size() != Cols)
      fail(source, row_field, "expected a row of " + std::to_string(Cols) + " integers");
    for (std::size_t c = 0; c < Cols; ++c)
      out[r][c] = read_int(row[c], source, row_field + "[" + std::to_string(c) + "]");
  }
}

}  // namespace

Configuration configuration_from_yaml(const std::string& text, const std::string& source) {
  const YAML::Node root = parse_yaml(text, source);
  if (!root.IsMap()) throw std::runtime_error(source + ": expected a mapping with C_a and C_s");
  for (const auto& item : root) {
    const std::string key = item.first.as<std::string>();
    if (key != "C_a" && key != "C_s" && key != "modules")
      fail(source, key, "unknown field (expected C_a and C_s, or modules)");
  }

  Configuration config;
  if (root["modules"]) {
    if (root["C_a"] || root["C_s"]) fail(source, "modules", "give either modules or C_a/C_s");
    const int n = read_int(root["modules"], source, "modules");
    try {
      config = make_chain(n);
    } catch (const std::invalid_argument& e) {
      fail(source, "modules", e.what());
    }
  } else {
    if (!root["C_a"]) fail(source, "C_a", "missing");
    if (!root["C_s"]) fail(source, "C_s", "missing");
    read_matrix(root["C_a"], source, "C_a", kMaxModules, config.C_a);
    read_matrix(root["C_s"], source, "C_s", 0, config.C_s);
  }
  if (std::string error = validate(config); !error.empty())
    throw std::runtime_error(source + ": invalid configuration: " + error);
  return config;
}

Configuration load_configuration(const std::string& path) {
  return configuration_from_yaml(read_text_file(path), path);
}

std::string to_yaml(const Configuration& config) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Comment("chain-type modular robot: C_a adjacency (10x10), C_s connections "
                       "(module_i, module_j, face_i, face_j, connection)");
  out << YAML::Key << "C_a" << YAML::Value << YAML::BeginSeq;
  for (const auto& row : config.C_a) out << YAML::Flow << std::vector<int>(row.begin(), row.end());
  out << YAML::EndSeq;
  out << YAML::Key << "C_s" << YAML::Value << YAML::BeginSeq;
  for (const auto& row : config.C_s) out << YAML::Flow << std::vector<int>(row.begin(), row.end());
  out << YAML::EndSeq;
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

void save_configuration(const std::string& path, const Configuration& config) {
  write_file_atomic(path, to_yaml(config));
}

}  // namespace comorph
