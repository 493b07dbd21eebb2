#include "common/yaml_fields.hpp"

#include <set>

namespace comorph {

std::string line_of(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.is_null() ? "" : " (line " + std::to_string(mark.line + 1) + ")";
}

void YamlFields::fail(const std::string& field, const std::string& what, const YAML::Node& node) const {
  fail(field, what + line_of(node));
}

void YamlFields::apply(const YAML::Node& map, const std::string& prefix) const {
  if (!map.IsDefined() || map.IsNull()) return;
  if (!map.IsMap()) fail(prefix.empty() ? "<root>" : prefix.substr(0, prefix.size() - 1), "expected a mapping", map);
  for (const auto& item : map) {
    const std::string key = prefix + item.first.Scalar();  // parse_yaml refused keys that are not names
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
    fail(key, is_prefix ? "expected a mapping" : "unknown field", item.first);
  }
}

void YamlFields::apply_text(const std::string& text) const { apply(parse_yaml(text, source_)); }

YAML::Node YamlFields::values() const {
  YAML::Node root(YAML::NodeType::Map);
  for (const auto& f : fields_) {
    YAML::Node node = root;
    std::size_t start = 0;
    for (std::size_t dot = f.name.find('.'); dot != std::string::npos; dot = f.name.find('.', start)) {
      const std::string part = f.name.substr(start, dot - start);
      if (!node[part]) node[part] = YAML::Node(YAML::NodeType::Map);
      node.reset(node[part]);
      start = dot + 1;
    }
    node[f.name.substr(start)] = f.get();
  }
  return root;
}

std::vector<Setting> YamlFields::settings() const {
  std::vector<Setting> list;
  for (const auto& f : fields_) {
    YAML::Emitter e;
    e.SetSeqFormat(YAML::Flow);
    e << f.get();
    list.push_back({f.name, f.type, f.range, e.c_str(), f.meaning});
  }
  return list;
}

namespace {

// Throws on the first mapping (at any depth) that has a key twice or a key
// that is not a name.
void check_keys(const YAML::Node& node, const std::string& source) {
  if (node.IsSequence()) {
    for (const auto& item : node) check_keys(item, source);
    return;
  }
  if (!node.IsMap()) return;
  std::set<std::string> seen;
  for (const auto& item : node) {
    const std::string line = std::to_string(item.first.Mark().line + 1);
    if (!item.first.IsScalar())
      throw std::runtime_error(source + ": line " + line + ": a key must be a name, not a " +
                               (item.first.IsSequence() ? "list" : item.first.IsMap() ? "mapping" : "null"));
    const std::string key = item.first.Scalar();
    if (!seen.insert(key).second)
      throw std::runtime_error(source + ": key '" + quote_value(key) + "' appears twice in one mapping (line " + line +
                               ")");
    check_keys(item.second, source);
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
  check_keys(root, source);
  return root;
}

YAML::Node load_yaml_file(const std::string& path) { return parse_yaml(read_text_file(path), path); }

}  // namespace comorph
