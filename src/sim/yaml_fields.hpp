// Binds the fields of a parameter struct to YAML keys with ranges, so that
// every config loader rejects unknown keys and out-of-range values with the
// file name and the field (yaml-cpp does the parsing).
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

namespace comorph::sim {

class YamlFields {
 public:
  explicit YamlFields(std::string source) : source_(std::move(source)) {}

  // `prefix` names nested maps in messages (e.g. "stair.w1").
  void add(const std::string& name, double* value, double min, double max);
  void add(const std::string& name, int* value, int min, int max);
  void add(const std::string& name, bool* value);

  // Applies a YAML mapping; throws std::runtime_error "<source>: field '<name>': ...".
  void apply(const YAML::Node& map, const std::string& prefix = "") const;
  // Parses text first (syntax errors name the source and the line).
  void apply_text(const std::string& text) const;

  [[noreturn]] void fail(const std::string& field, const std::string& what) const;
  const std::string& source() const { return source_; }

 private:
  struct Field {
    std::string name;
    double* d = nullptr;
    int* i = nullptr;
    bool* b = nullptr;
    double min = 0, max = 0;
  };
  std::string source_;
  std::vector<Field> fields_;
};

// Reads a whole file; throws std::runtime_error naming the file when it cannot.
std::string read_text_file(const std::string& path);

}  // namespace comorph::sim
