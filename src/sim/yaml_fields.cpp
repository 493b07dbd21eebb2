#include "sim/yaml_fields.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace comorph::sim {

void YamlFields::add(const std::string& name, double* value, double min, double max) {
  fields_.push_back({name, value, nullptr, nullptr, min, max});
}
void YamlFields::add(const std::string& name, int* value, int min, int max) {
  fields_.push_back({name, nullptr, value, nullptr, double(min), double(max)});
}
void YamlFields::add(const std::string& name, bool* value) {
  fields_.push_back({name, nullptr, nullptr, value, 0, 1});
}

void YamlFields::fail(const std::string& field, const std::string& what) const {
  throw std::runtime_error(source_ + ": field '" + field + "': " + what);
}

void YamlFields::apply(const YAML::Node& map, const std::string& prefix) const {
  if (!map.IsDefined() || map.IsNull()) return;
  if (!map.IsMap()) fail(prefix.empty() ? "<root>" : prefix, "expected a mapping");
  for (const auto& item : map) {
    const std::string key = prefix + item.first.as<std::string>();
    const Field* field = nullptr;
    for (const auto& f : fields_)
      if (f.name == key) field = &f;
    if (!field) {
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
    if (!item.second.IsScalar()) fail(key, "expected a number");
    try {
      if (field->b) {
        *field->b = item.second.as<bool>();
        continue;
      }
      const double v = field->i ? double(item.second.as<int>()) : item.second.as<double>();
      if (!(v >= field->min && v <= field->max)) {
        std::ostringstream os;
        os << "value " << v << " out of range [" << field->min << ", " << field->max << "]";
        fail(key, os.str());
      }
      if (field->i) *field->i = int(v);
      else *field->d = v;
    } catch (const YAML::Exception&) {
      fail(key, "'" + item.second.Scalar() + "' is not a " +
                    (field->b ? "boolean" : field->i ? "integer" : "number"));
    }
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

}  // namespace comorph::sim
