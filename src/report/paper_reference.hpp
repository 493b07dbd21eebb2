// The paper's Tables I and II, kept in configs/reference/paper-tables.yaml,
// and which of our runs each column is compared with.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace comorph::report {

// Which run a paper column corresponds to (fields of the run's run.yaml).
struct RunMatch {
  std::string kind;           // hierarchical | fixed
  int modules = 0;            // modules of a fixed run; 0 = any
  std::string algo;           // td3 | sac
  std::string eval_scenario;  // read from eval-<eval_scenario>.json
  std::string train_scenario = "default";  // the run's training scenario (run.yaml `scenario`)
};

// One column of a paper table. Values the paper does not give are NaN / absent.
struct PaperColumn {
  std::string label;                               // e.g. "Fixed 4"
  RunMatch match;
  double time_s;                                   // mean time of successful episodes, seconds
  double energy_J;                                 // mean battery use of successful episodes, joules
  std::map<std::string, double> success_percent;   // "0.04", "0.06", "0.08", "avg" -> percent
  double F;                                        // F(H), dimensionless
  std::map<std::string, std::string> configurations;  // stair key -> sequence ("4->2"), when given
};

struct PaperTable {
  int id = 0;            // 1 or 2
  std::string title;
  std::vector<PaperColumn> columns;
};

struct PaperReference {
  std::string source;
  std::string protocol;
  std::vector<PaperTable> tables;
  std::vector<std::string> notes;
};

// configs/reference/paper-tables.yaml of resource_dir() (common/resources.hpp).
std::string default_paper_reference_path();

// Throws naming the file and the offending entry when it is missing or malformed.
PaperReference load_paper_reference(const std::string& path);

}  // namespace comorph::report
