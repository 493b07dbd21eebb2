#include "common/yaml_fields.hpp"

#include <set>

namespace comorph {

void YamlFields::apply(const YAML::Node& map, const std::string& prefix) const {
  if (!map.IsDefined() || map.IsNull()) return;
  if (!map.IsMap()) fail(prefix.empty() ? "<root>" : prefix, "expected a mapping");
  for (const auto& item : map) {
    const std::string key = prefix + item.first.as<std::string>();
    const Field* field = nullptr;
    for (const auto& f : fields_)
      if (f.name == key) field = &f;
    if (field) {
      field->set(item.second, key);
      continue;
    }
    // A nested map whose keys are known fields with this prefix.
    bool is_prefix = false;
    for (const auto& f : fields_)
      if (f.name.rfind(key + ".", 0) == 0) is_prefix = true;
    if (is_prefix && item.second.IsMap()) {
      apply(item.second, key + ".");
      continue;
    }
    fail(key, "unknown field");
  }
}

void YamlFields::apply_text(const std::string& text) const { apply(parse_yaml(text, source_)); }

namespace {

// Throws on the first mapping (at any depth) that has a key twice.
void check_unique_keys(const YAML::Node& node, const std::string& source) {
  if (node.IsSequence()) {
    for (const auto& item : node) check_unique_keys(item, source);
    return;
  }
  if (!node.IsMap()) return;
  std::set<std::string> seen;
  for (const auto& item : node) {
    const std::string key = item.first.IsScalar() ? item.first.Scalar() : YAML::Dump(item.first);
    if (!seen.insert(key).second)
      throw std::runtime_error(source + ": key '" + quote_value(key) + "' appears twice in one mapping (line " +
                               std::to_string(item.first.Mark().line + 1) + ")");
    check_unique_keys(item.second, source);
  }
}

}  // namespace

YAML::Node parse_yaml(const std::string& text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(source + ": not valid YAML: " + e.msg + " (line " + std::to_string(e.mark.line + 1) +
                             ")");
  }
  check_unique_keys(root, source);
  return root;
}

YAML::Node load_yaml_file(const std::string& path) { return parse_yaml(read_text_file(path), path); }

}  // namespace comorph
