#include "common/yaml_fields.hpp"

#include <fstream>

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

void YamlFields::apply_text(const std::string& text) const {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(source_ + ": not valid YAML: " + e.msg + " (line " +
                             std::to_string(e.mark.line + 1) + ")");
  }
  apply(root);
}

std::string read_text_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open file");
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

YAML::Node load_yaml_file(const std::string& path) {
  const std::string text = read_text_file(path);
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(path + ": not valid YAML: " + e.msg + " (line " +
                             std::to_string(e.mark.line + 1) + ")");
  }
}

}  // namespace comorph
