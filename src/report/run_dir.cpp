#include "report/run_dir.hpp"

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>

#include "common/yaml_fields.hpp"  // load_yaml_file, write_file_atomic
#include "morphology/configuration.hpp"

namespace fs = std::filesystem;

namespace comorph::report {

RunInfo read_run_info(const std::string& path, const std::string& default_name) {
  const YAML::Node root = load_yaml_file(path);  // size cap, duplicate keys
  if (!root.IsMap()) throw std::runtime_error(fmt::format("{}: expected a map of fields", path));
  auto text = [&](const char* key, bool required, const std::string& fallback) {
    if (!root[key]) {
      if (required) throw std::runtime_error(fmt::format("{}: missing field '{}'", path, key));
      return fallback;
    }
    return root[key].as<std::string>();
  };
  auto integer = [&](const char* key) {
    if (!root[key]) return 0;
    try {
      return root[key].as<int>();
    } catch (const YAML::Exception&) {
      throw std::runtime_error(fmt::format("{}: field '{}' is not an integer", path, key));
    }
  };
  RunInfo info;
  info.name = text("name", false, default_name);
  info.kind = text("kind", true, "");
  if (info.kind != "hierarchical" && info.kind != "fixed")
    throw std::runtime_error(fmt::format("{}: kind '{}' is not hierarchical or fixed", path, info.kind));
  info.modules = integer("modules");
  if (info.kind == "fixed" && (info.modules < kMinModules || info.modules > kMaxModules))
    throw std::runtime_error(fmt::format("{}: a fixed run needs modules in {}..{} (got {})", path, kMinModules,
                                         kMaxModules, info.modules));
  info.algo = text("algo", true, "");
  if (info.algo != "td3" && info.algo != "sac")
    throw std::runtime_error(fmt::format("{}: algo '{}' is not td3 or sac", path, info.algo));
  info.scenario = text("scenario", false, "default");
  info.episodes = integer("episodes");
  info.preset = text("preset", false, "");
  info.notes = text("notes", false, "");
  return info;
}

void write_run_info(const std::string& path, const RunInfo& info) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "name" << YAML::Value << info.name;
  out << YAML::Key << "kind" << YAML::Value << info.kind;
  out << YAML::Key << "modules" << YAML::Value << info.modules;
  out << YAML::Key << "algo" << YAML::Value << info.algo;
  out << YAML::Key << "scenario" << YAML::Value << info.scenario;
  if (info.episodes > 0) out << YAML::Key << "episodes" << YAML::Value << info.episodes;
  if (!info.preset.empty()) out << YAML::Key << "preset" << YAML::Value << info.preset;
  if (!info.notes.empty()) out << YAML::Key << "notes" << YAML::Value << info.notes;
  out << YAML::EndMap;
  write_file_atomic(path, std::string(out.c_str()) + "\n");
}

namespace {

// trainer.seed of a config.yaml; 0 when it has none.
int config_seed(const std::string& path) {
  const YAML::Node root = load_yaml_file(path);
  const YAML::Node trainer = root.IsMap() ? root["trainer"] : YAML::Node();
  if (!trainer.IsMap() || !trainer["seed"]) return 0;
  try {
    return trainer["seed"].as<int>();
  } catch (const YAML::Exception&) {
    throw std::runtime_error(fmt::format("{}: trainer.seed is not an integer", path));
  }
}

}  // namespace

std::string config_as_written(const std::string& path) {
  YAML::Node root = load_yaml_file(path);
  if (root.IsMap() && root["trainer"].IsMap()) root["trainer"].remove("seed");
  return YAML::Dump(root);
}

RunDir load_run_dir(const std::string& path, const ConfigIdentity& identity) {
  if (!fs::is_directory(path)) throw std::runtime_error(fmt::format("run directory {} does not exist", path));
  RunDir run;
  run.path = path;
  const fs::path dir(path);
  std::vector<std::string> missing;
  const fs::path yaml = dir / "run.yaml";
  // An exported run (`comorph export`, results/) keeps its log as episodes.csv.gz.
  const fs::path csv = fs::is_regular_file(dir / "episodes.csv.gz") && !fs::exists(dir / "episodes.csv")
                           ? dir / "episodes.csv.gz"
                           : dir / "episodes.csv";
  if (!fs::is_regular_file(yaml)) missing.push_back(yaml.string());
  if (!fs::is_regular_file(csv)) missing.push_back(csv.string());
  std::vector<fs::path> evals;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_regular_file() && name.rfind("eval-", 0) == 0 && entry.path().extension() == ".json")
      evals.push_back(entry.path());
  }
  if (evals.empty()) missing.push_back((dir / "eval-<scenario>.json").string() + " (none found)");
  if (!missing.empty())
    throw std::runtime_error(fmt::format("run directory {} is incomplete; missing: {} (layout: docs/report.md)", path,
                                         fmt::join(missing, ", ")));
  fs::path name = dir.filename().empty() ? dir.parent_path().filename() : dir.filename();
  run.info = read_run_info(yaml.string(), name.string());
  run.episodes_csv = csv.string();
  for (const auto& e : evals) {
    const std::string stem = e.stem().string();  // eval-<scenario>
    run.evals[stem.substr(5)] = read_metrics_json(e.string());
  }
  const fs::path config = dir / "config.yaml";
  if (fs::is_regular_file(config)) {
    run.seed = config_seed(config.string());
    run.config_key = identity ? identity(config.string()) : config_as_written(config.string());
  }
  return run;
}

}  // namespace comorph::report
