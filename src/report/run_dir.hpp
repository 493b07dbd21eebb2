// A run directory as the trainer/evaluator leaves it (layout: docs/report.md):
//   run.yaml             what the run is (RunInfo below)
//   episodes.csv         one row per training episode (episode_record.hpp);
//                        episodes.csv.gz in an exported run (results/)
//   eval-<scenario>.json one evaluation summary per test scenario (metrics.hpp)
//   config.yaml          optional here: the run's configuration (its training seed)
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "report/metrics.hpp"

namespace comorph::report {

// run.yaml. Example:
//   name: hier-td3        # optional; default: the directory's name
//   kind: hierarchical    # hierarchical | fixed
//   modules: 10           # fixed: the chain's modules; hierarchical: most modules it may choose (C_n)
//   algo: td3             # td3 | sac (motion learner)
//   scenario: default     # training scenario: default | obstacles7 | obstacles8 | mixed
//   episodes: 4300        # optional: training episodes run (warm-up included)
//   preset: quick         # optional: config preset used
//   notes: "..."          # optional free text shown in the report
struct RunInfo {
  std::string name;
  std::string kind;
  int modules = 0;
  std::string algo;
  std::string scenario = "default";
  int episodes = 0;  // 0 = not given
  std::string preset;
  std::string notes;
};

struct RunDir {
  std::string path;
  RunInfo info;
  std::map<std::string, EvalSummary> evals;  // test scenario -> its eval-<scenario>.json
  std::string episodes_csv;              // path of episodes.csv (or episodes.csv.gz)
  // From config.yaml when the run has one: its trainer.seed (0: no
  // config.yaml), and the configuration without that seed (ConfigIdentity),
  // so that the runs of one configuration trained with different seeds can be
  // told from the runs of another ("" without config.yaml).
  int seed = 0;
  std::string config_key;
};

// The configuration of a config.yaml without its trainer.seed, as text that
// is equal for equal settings. The report layer does not know the settings'
// defaults, so by default it compares the file as written; the app passes
// coopt::config_identity, which resolves the file first (a run written before
// configs were resolved then groups with a resolved one of the same settings).
using ConfigIdentity = std::function<std::string(const std::string& config_yaml_path)>;
std::string config_as_written(const std::string& config_yaml_path);

RunInfo read_run_info(const std::string& run_yaml_path, const std::string& default_name);
void write_run_info(const std::string& run_yaml_path, const RunInfo& info);

// Checks and reads a run directory: throws naming every missing file
// (run.yaml, episodes.csv, at least one eval-*.json) or the malformed one.
// `identity`: how config.yaml becomes RunDir::config_key (empty: config_as_written).
RunDir load_run_dir(const std::string& path, const ConfigIdentity& identity = {});

}  // namespace comorph::report
