// run_experiment (experiment.hpp): the paper tables' columns as run directories.
#include "workflows/experiment.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "common/file_io.hpp"
#include "common/run_lock.hpp"
#include "coopt/config.hpp"
#include "coopt/trainer.hpp"
#include "report/paper_reference.hpp"
#include "report/report.hpp"
#include "report/run_dir.hpp"
#include "workflows/run_steps.hpp"

namespace comorph::workflows {
namespace {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// One run of an experiment: a run directory, the keys that make it that run
// (applied after the user's --set), the test scenarios it is evaluated on.
struct Column {
  std::string name;
  std::vector<std::string> sets;
  std::vector<std::string> scenarios;
};

// The runs a paper table compares with, derived from the `match` of its
// columns in configs/reference/paper-tables.yaml: the matrix is that data, so a
// column added there is trained here. Columns that match the same run (Table
// II's TD3 hierarchy on three scenarios) become one run with several evaluations.
std::vector<Column> columns_of_table(const comorph::report::PaperReference& paper, int table) {
  const comorph::report::PaperTable* found = nullptr;
  std::string ids;
  for (const auto& t : paper.tables) {
    ids += (ids.empty() ? "" : " or ") + std::to_string(t.id);
    if (t.id == table) found = &t;
  }
  if (!found) throw std::runtime_error(fmt::format("experiment: --table must be {}, got {}", ids, table));
  std::vector<Column> columns;
  for (const auto& paper_column : found->columns) {
    const auto& m = paper_column.match;
    Column c;
    if (m.kind == "hierarchical") {
      c.name = "hier-" + m.algo;
      c.sets = {"trainer.mode=hierarchical", "trainer.motion_algo=" + m.algo};
    } else if (m.kind == "fixed" && m.modules > 0) {
      c.name = fmt::format("fixed-{}", m.modules) + (m.algo == "td3" ? "" : "-" + m.algo);
      // A fixed chain has no DQN, so no DQN refit either: its motion model gets
      // the hierarchy's budget (warm-up + training episodes; the refit's are the DQN's alone).
      c.sets = {"trainer.mode=fixed", fmt::format("trainer.fixed_modules={}", m.modules),
                "trainer.motion_algo=" + m.algo, "trainer.config_refit_episodes=0"};
    } else {
      throw std::runtime_error(fmt::format("{}: table {}, column '{}': match needs kind hierarchical, or fixed with "
                                           "modules, to be trained (got kind '{}', modules {})",
                                           comorph::report::default_paper_reference_path(), table,
                                           paper_column.label, m.kind, m.modules));
    }
    // A run trained in another scenario than the default is its own run.
    if (m.train_scenario != "default") {
      c.name += "-" + m.train_scenario;
      c.sets.push_back("trainer.scenario=" + m.train_scenario);
    }
    auto same = std::find_if(columns.begin(), columns.end(), [&](const Column& o) { return o.name == c.name; });
    if (same == columns.end()) same = columns.insert(columns.end(), c);
    if (std::find(same->scenarios.begin(), same->scenarios.end(), m.eval_scenario) == same->scenarios.end())
      same->scenarios.push_back(m.eval_scenario);
  }
  return columns;
}

// What happened to one column in this call (for the closing summary).
struct ColumnTimes {
  std::string name;
  std::string training;    // "trained", "resumed", "done before"
  double train_wall_s = 0; // the run's whole training wall time (all resumed parts), s
  long long env_steps = 0;
  double eval_wall_s = 0;  // evaluations run in this call, s
};

// The user's --set list, then the column's keys.
std::vector<std::string> column_sets(const ExperimentOptions& o, const Column& column) {
  std::vector<std::string> sets = o.sets;
  sets.insert(sets.end(), column.sets.begin(), column.sets.end());
  return sets;
}

// Makes sure the column's run is fully trained; false when interrupted.
// `expected` is the column's config (--config + column_sets).
bool train_column(const ExperimentOptions& o, const Column& column, const comorph::coopt::CooptConfig& expected,
                  const std::string& run_dir, ColumnTimes& times) {
  const int total = expected.trainer.total_episodes();

  if (!is_empty_run_dir(run_dir)) {
    const fs::path existing_config = fs::path(run_dir) / "config.yaml";
    if (!fs::exists(existing_config))
      throw std::runtime_error(run_dir + " exists and is not a training run (no config.yaml); move it away");
    if (comorph::coopt::load_coopt_config(existing_config.string()).text != expected.text)
      throw std::runtime_error(run_dir + " was trained with another configuration than --config/--set give now (" +
                               existing_config.string() + "); use another --out or remove it");
    // Only a run without any checkpoint starts again: a damaged checkpoint is
    // refused (read_checkpoint_info names the file), never thrown away.
    std::optional<comorph::coopt::CheckpointInfo> checkpoint;
    if (fs::exists(fs::path(run_dir) / "checkpoint") || fs::exists(fs::path(run_dir) / "checkpoint.old"))
      checkpoint = comorph::coopt::read_checkpoint_info(run_dir);
    if (!checkpoint) {
      // Interrupted before its first checkpoint: nothing to resume.
      std::fprintf(stderr, "experiment: %s has no checkpoint yet; starting it again\n", run_dir.c_str());
      clear_run_dir(run_dir);  // keeps the lock file this call holds
    } else if (checkpoint->episodes >= total) {
      comorph::coopt::check_checkpoint_counts(*checkpoint, expected);
      times.training = "done before";
      return true;
    } else {
      times.training = "resumed";
      return train_run("", {}, "", run_dir, true);
    }
  }
  times.training = "trained";
  return train_run(o.config, column_sets(o, column), run_dir, "", true);
}

}  // namespace

bool run_experiment(const ExperimentOptions& o) {
  const auto paper = comorph::report::load_paper_reference(comorph::report::default_paper_reference_path());
  std::vector<Column> columns = columns_of_table(paper, o.table);
  if (!o.only.empty()) {
    std::vector<Column> picked;
    std::string names;
    for (const auto& c : columns) {
      names += (names.empty() ? "" : ", ") + c.name;
      if (c.name == o.only) picked.push_back(c);
    }
    if (picked.empty())
      throw std::runtime_error(fmt::format("experiment: table {} has no column '{}' (columns: {})", o.table, o.only, names));
    columns = picked;
  }
  // Every column's config is checked before hours of training start.
  std::vector<comorph::coopt::CooptConfig> configs;
  for (const auto& c : columns) configs.push_back(comorph::coopt::load_coopt_config(o.config, column_sets(o, c)));
  fs::create_directories(o.out);

  std::vector<ColumnTimes> times;
  for (std::size_t i = 0; i < columns.size(); ++i) {
    const Column& column = columns[i];
    const std::string run_dir = (fs::path(o.out) / column.name).string();
    std::fprintf(stderr, "experiment: column %zu/%zu: %s\n", i + 1, columns.size(), run_dir.c_str());
    ColumnTimes t;
    t.name = column.name;
    // One writer per column for its training and its evaluations.
    fs::create_directories(run_dir);
    const comorph::RunLock lock(run_dir);
    if (!train_column(o, column, configs[i], run_dir, t)) {
      std::fprintf(stderr, "experiment interrupted in %s (checkpoint written); run the same command again to continue\n",
                   run_dir.c_str());
      return false;
    }
    const auto info = comorph::coopt::read_checkpoint_info(run_dir);
    t.train_wall_s = info.wall_s;
    t.env_steps = static_cast<long long>(info.env_steps);
    for (const auto& scenario : column.scenarios) {
      if (fs::exists(fs::path(run_dir) / ("eval-" + scenario + ".json"))) continue;
      const auto start = Clock::now();
      eval_run(run_dir, scenario, o.eval_episodes, o.eval_seed, 0);
      t.eval_wall_s += std::chrono::duration<double>(Clock::now() - start).count();
    }
    times.push_back(t);
  }

  // The table of this experiment, ours beside the paper's, and the report,
  // from every column directory of either table that is complete (a --only
  // call, or one table of two, shows what exists so far).
  std::vector<comorph::report::RunDir> runs;
  std::vector<std::string> run_dirs;
  for (const auto& table : paper.tables)
    for (const auto& column : columns_of_table(paper, table.id)) {
      const std::string dir = (fs::path(o.out) / column.name).string();
      if (std::find(run_dirs.begin(), run_dirs.end(), dir) != run_dirs.end()) continue;
      try {
        runs.push_back(comorph::report::load_run_dir(dir));
        run_dirs.push_back(dir);
      } catch (const std::exception&) {
        // not trained or evaluated yet: its cells show "—"
      }
    }
  std::string table_md;
  for (const auto& t : paper.tables) {
    if (t.id != o.table) continue;
    comorph::report::ReportBlock title;
    title.kind = comorph::report::ReportBlock::Kind::Heading;
    title.text = t.title + " (ours / paper)";
    table_md = comorph::report::render_markdown({title, comorph::report::comparison_table(t, runs)});
  }
  const fs::path table_path = fs::path(o.out) / fmt::format("table-{}.md", o.table);
  comorph::write_file_atomic(table_path.string(), table_md);

  std::printf("\n%s\n", table_md.c_str());
  std::printf("%-10s %-12s %14s %14s %12s\n", "column", "training", "train wall s", "control steps", "eval wall s");
  double train_total = 0, eval_total = 0;
  for (const auto& t : times) {
    std::printf("%-10s %-12s %14.0f %14lld %12.0f\n", t.name.c_str(), t.training.c_str(), t.train_wall_s, t.env_steps,
                t.eval_wall_s);
    train_total += t.train_wall_s;
    eval_total += t.eval_wall_s;
  }
  std::printf("%-10s %-12s %14.0f %14s %12.0f  (training: all parts of each run; eval: this call only)\n", "total", "",
              train_total, "", eval_total);

  if (!run_dirs.empty()) {
    comorph::report::ReportOptions report;
    report.out_dir = (fs::path(o.out) / "report").string();
    report.require_plots = false;
    const auto written = comorph::report::write_report(run_dirs, report);
    std::printf("wrote %s, %s and %s\n", table_path.c_str(), written.markdown_path.c_str(), written.html_path.c_str());
  }
  return true;
}

}  // namespace comorph::workflows
