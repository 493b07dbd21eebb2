#include "report/paper_reference.hpp"

#include <yaml-cpp/yaml.h>

#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "common/resources.hpp"
#include "common/yaml_fields.hpp"  // load_yaml_file

namespace comorph::report {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

template <typename T>
T get(const YAML::Node& node, const std::string& key, const std::string& where) {
  if (!node[key]) throw std::runtime_error(fmt::format("{}: missing '{}'", where, key));
  try {
    return node[key].as<T>();
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(fmt::format("{}: '{}' has the wrong type ({})", where, key, e.msg));
  }
}

double get_or_nan(const YAML::Node& node, const std::string& key, const std::string& where) {
  return node[key] ? get<double>(node, key, where) : kNaN;
}

}  // namespace

std::string default_paper_reference_path() { return resource_path("configs/reference/paper-tables.yaml"); }

PaperReference load_paper_reference(const std::string& path) {
  const YAML::Node root = load_yaml_file(path);  // size cap, duplicate keys
  PaperReference ref;
  ref.source = get<std::string>(root, "source", path);
  if (root["protocol"]) ref.protocol = get<std::string>(root, "protocol", path);
  if (root["notes"]) ref.notes = get<std::vector<std::string>>(root, "notes", path);
  const YAML::Node tables = root["tables"];
  if (!tables || !tables.IsSequence() || tables.size() == 0)
    throw std::runtime_error(fmt::format("{}: 'tables' must be a non-empty list", path));
  for (size_t t = 0; t < tables.size(); ++t) {
    const std::string where_t = fmt::format("{}: tables[{}]", path, t);
    PaperTable table;
    table.id = get<int>(tables[t], "id", where_t);
    table.title = get<std::string>(tables[t], "title", where_t);
    const YAML::Node columns = tables[t]["columns"];
    if (!columns || !columns.IsSequence() || columns.size() == 0)
      throw std::runtime_error(fmt::format("{}: 'columns' must be a non-empty list", where_t));
    for (size_t c = 0; c < columns.size(); ++c) {
      const YAML::Node col = columns[c];
      const std::string where = fmt::format("{}.columns[{}]", where_t, c);
      PaperColumn pc;
      pc.label = get<std::string>(col, "label", where);
      const YAML::Node match = col["match"];
      if (!match || !match.IsMap()) throw std::runtime_error(fmt::format("{}: missing 'match'", where));
      pc.match.kind = get<std::string>(match, "kind", where + ".match");
      pc.match.algo = get<std::string>(match, "algo", where + ".match");
      pc.match.eval_scenario = get<std::string>(match, "eval", where + ".match");
      if (match["modules"]) pc.match.modules = get<int>(match, "modules", where + ".match");
      if (match["train"]) pc.match.train_scenario = get<std::string>(match, "train", where + ".match");
      pc.time_s = get_or_nan(col, "time_s", where);
      pc.energy_J = get_or_nan(col, "energy_J", where);
      pc.F = get_or_nan(col, "F", where);
      if (col["success"]) pc.success_percent = get<std::map<std::string, double>>(col, "success", where);
      if (col["configurations"])
        pc.configurations = get<std::map<std::string, std::string>>(col, "configurations", where);
      table.columns.push_back(std::move(pc));
    }
    ref.tables.push_back(std::move(table));
  }
  return ref;
}

}  // namespace comorph::report
