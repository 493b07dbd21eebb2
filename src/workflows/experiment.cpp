// run_experiment (experiment.hpp): the paper tables' columns as run directories.
#include "workflows/experiment.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

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

// One run of the experiment: a column trained with one seed, in its own directory.
struct ExperimentRun {
  Column column;
  int seed = 0;                   // 0: the config's trainer.seed (no --seeds)
  std::string dir;                // out/COLUMN, or out/COLUMN-seed-S
  std::vector<std::string> sets;  // the user's --set, the column's keys, trainer.seed
};

// Written into a run directory once it is trained and evaluated on all its
// scenarios: such a run is never trained again.
constexpr const char* kFinishedFile = "finished";

// Every column of `table` times every seed, in the table's order.
std::vector<ExperimentRun> runs_of_table(const ExperimentOptions& o, const comorph::report::PaperReference& paper,
                                         int table) {
  std::vector<ExperimentRun> runs;
  for (const Column& column : columns_of_table(paper, table)) {
    std::vector<std::string> sets = o.sets;
    sets.insert(sets.end(), column.sets.begin(), column.sets.end());
    if (o.seeds.empty()) {
      runs.push_back({column, 0, (fs::path(o.out) / column.name).string(), sets});
      continue;
    }
    for (int seed : o.seeds) {
      ExperimentRun run{column, seed, (fs::path(o.out) / fmt::format("{}-seed-{}", column.name, seed)).string(), sets};
      run.sets.push_back(fmt::format("trainer.seed={}", seed));
      runs.push_back(run);
    }
  }
  return runs;
}

// The runs this call trains: the table's, or only the --only column's.
std::vector<ExperimentRun> selected_runs(const ExperimentOptions& o, const comorph::report::PaperReference& paper) {
  std::vector<ExperimentRun> runs = runs_of_table(o, paper, o.table);
  if (o.only.empty()) return runs;
  std::vector<ExperimentRun> picked;
  std::vector<std::string> names;
  for (const auto& r : runs) {
    if (std::find(names.begin(), names.end(), r.column.name) == names.end()) names.push_back(r.column.name);
    if (r.column.name == o.only) picked.push_back(r);
  }
  if (picked.empty())
    throw std::runtime_error(
        fmt::format("experiment: table {} has no column '{}' (columns: {})", o.table, o.only, fmt::join(names, ", ")));
  return picked;
}

// What happened to one run in this call (for the closing summary).
struct RunTimes {
  std::string name;
  std::string training;    // "trained", "resumed", "done before"
  double train_wall_s = 0; // the run's whole training wall time (all resumed parts), s
  long long env_steps = 0;
  double eval_wall_s = 0;  // evaluations run in this call, s
};

// Makes sure the run is fully trained; false when interrupted. `expected` is
// its config (--config + its sets).
bool train_experiment_run(const ExperimentOptions& o, const ExperimentRun& run,
                          const comorph::coopt::CooptConfig& expected, RunTimes& times) {
  const std::string& run_dir = run.dir;
  if (!is_empty_run_dir(run_dir)) {
    const fs::path existing_config = fs::path(run_dir) / "config.yaml";
    if (!fs::exists(existing_config))
      throw std::runtime_error(run_dir + " exists and is not a training run (no config.yaml); move it away");
    if (comorph::coopt::load_coopt_config(existing_config.string()).text != expected.text)
      throw std::runtime_error(run_dir + " was trained with another configuration than --config/--set give now (" +
                               existing_config.string() + "); use another --out or remove it");
    if (fs::exists(fs::path(run_dir) / kFinishedFile)) {
      times.training = "done before";
      return true;
    }
    // Only a run without any checkpoint starts again: a damaged checkpoint is
    // refused (read_checkpoint_info names the file), never thrown away.
    std::optional<comorph::coopt::CheckpointInfo> checkpoint;
    if (fs::exists(fs::path(run_dir) / "checkpoint") || fs::exists(fs::path(run_dir) / "checkpoint.old"))
      checkpoint = comorph::coopt::read_checkpoint_info(run_dir);
    if (!checkpoint) {
      // Interrupted before its first checkpoint: nothing to resume.
      std::fprintf(stderr, "experiment: %s has no checkpoint yet; starting it again\n", run_dir.c_str());
      clear_run_dir(run_dir);  // keeps the lock file this call holds and the job's log
    } else if (checkpoint->episodes >= expected.trainer.total_episodes()) {
      comorph::coopt::check_checkpoint_counts(*checkpoint, expected);
      times.training = "done before";
      return true;
    } else {
      times.training = "resumed";
      return train_run("", {}, "", run_dir, true);
    }
  }
  times.training = "trained";
  return train_run(o.config, run.sets, run_dir, "", true);
}

// Why `run` is not in the table yet; "" when it is trained and evaluated on
// every scenario of its column.
std::string missing_reason(const ExperimentRun& run) {
  const fs::path dir(run.dir);
  if (!fs::exists(dir / "config.yaml")) return "not started";
  std::vector<std::string> lacking;
  for (const auto& scenario : run.column.scenarios)
    if (!fs::exists(dir / ("eval-" + scenario + ".json"))) lacking.push_back(scenario);
  if (lacking.empty()) return "";
  if (!fs::exists(dir / "checkpoint") && !fs::exists(dir / "checkpoint.old")) return "started, no checkpoint yet";
  try {
    const auto checkpoint = comorph::coopt::read_checkpoint_info(run.dir);
    const auto info = comorph::report::read_run_info((dir / "run.yaml").string(), dir.filename().string());
    if (checkpoint.episodes < info.episodes)
      return fmt::format("trained {} of {} episodes", checkpoint.episodes, info.episodes);
  } catch (const std::exception& e) {
    return std::string("checkpoint unreadable: ") + e.what();
  }
  return fmt::format("trained, not evaluated on {}", fmt::join(lacking, ", "));
}

// The table of o.table beside the paper's in out/table-N.md and the report
// in out/report/, from what exists: o.runs, or else the runs of either table
// under o.out that are complete (others are named as missing).
void collect(const ExperimentOptions& o, const comorph::report::PaperReference& paper) {
  std::vector<std::string> run_dirs, missing;
  std::vector<comorph::report::RunDir> runs;
  if (!o.runs.empty()) {
    for (const auto& dir : o.runs) {
      // A run named twice (runs/x and runs/x/) would count as two seeds.
      const bool again = std::any_of(run_dirs.begin(), run_dirs.end(), [&](const std::string& d) {
        return fs::weakly_canonical(d) == fs::weakly_canonical(dir);
      });
      if (again) continue;
      try {
        runs.push_back(comorph::report::load_run_dir(dir, comorph::coopt::config_identity));
        run_dirs.push_back(dir);
      } catch (const std::exception& e) {
        missing.push_back(e.what());
      }
    }
  } else {
    for (const auto& table : paper.tables)
      for (const auto& run : runs_of_table(o, paper, table.id)) {
        if (std::find(run_dirs.begin(), run_dirs.end(), run.dir) != run_dirs.end()) continue;
        std::string why = missing_reason(run);
        if (why.empty()) {
          try {
            runs.push_back(comorph::report::load_run_dir(run.dir, comorph::coopt::config_identity));
            run_dirs.push_back(run.dir);
          } catch (const std::exception& e) {
            why = e.what();
          }
        }
        if (!why.empty() && table.id == o.table) missing.push_back(run.dir + ": " + why);
      }
  }
  std::string table_md;
  for (const auto& t : paper.tables) {
    if (t.id != o.table) continue;
    if (!o.runs.empty())
      for (const auto& column : t.columns)
        if (comorph::report::column_runs(column, runs).empty())
          missing.push_back(fmt::format("column '{}': no run given", column.label));
    comorph::report::ReportBlock title, legend, lacking;
    title.kind = comorph::report::ReportBlock::Kind::Heading;
    title.text = t.title + " (ours / paper)";
    legend.text = comorph::report::comparison_table_legend();
    std::vector<comorph::report::ReportBlock> blocks = {title, comorph::report::comparison_table(t, runs), legend};
    if (!missing.empty()) {
      lacking.text = fmt::format("Missing, so not in the table: {}.", fmt::join(missing, "; "));
      blocks.push_back(lacking);
    }
    table_md = comorph::report::render_markdown(blocks);
  }
  fs::create_directories(o.out);
  const fs::path table_path = fs::path(o.out) / fmt::format("table-{}.md", o.table);
  comorph::write_file_atomic(table_path.string(), table_md);
  std::printf("\n%s\n", table_md.c_str());
  if (run_dirs.empty()) {
    std::printf("wrote %s (no run is complete yet: no report)\n", table_path.c_str());
    return;
  }
  comorph::report::ReportOptions report;
  report.out_dir = (fs::path(o.out) / "report").string();
  report.require_plots = false;
  report.missing = missing;
  report.config_identity = comorph::coopt::config_identity;
  const auto written = comorph::report::write_report(run_dirs, report);
  std::printf("wrote %s, %s and %s\n", table_path.c_str(), written.markdown_path.c_str(), written.html_path.c_str());
}

// `text` as one word of a POSIX shell command line.
std::string shell_word(const std::string& text) {
  const bool plain = !text.empty() && std::all_of(text.begin(), text.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || std::string("_./=:,+-@%").find(c) != std::string::npos;
  });
  if (plain) return text;
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

std::string command_line(const std::vector<std::string>& words) {
  std::vector<std::string> quoted;
  for (const auto& w : words) quoted.push_back(shell_word(w));
  return fmt::format("{}", fmt::join(quoted, " "));
}

// Cores one job keeps busy: its training's threads (the simulation threads and
// the learner thread, each with its torch threads) or its evaluation's
// workers, whichever is more.
int job_cores(const comorph::coopt::CooptConfig& c, const std::string& source) {
  if (c.eval.workers <= 0)
    throw std::runtime_error(source + ": eval.workers is 0 (one per core of the machine); a job states its cores: "
                             "set eval.workers (e.g. --set eval.workers=2)");
  const int training = (c.trainer.simulation_threads + (c.trainer.learner_thread ? 1 : 0)) * c.trainer.torch_threads;
  return std::max(training, c.eval.workers);
}

std::string cores_text(int n) { return fmt::format("{} core{}", n, n == 1 ? "" : "s"); }

// Writes o.jobs_file (one shell command line per run) and/or o.slurm_file
// (a Slurm array job, task i runs line i); each job trains and evaluates its
// run with `--only COLUMN [--seeds S] --no-table`, logging to its run
// directory's job log. Paths are absolute and each line starts in this
// directory, so relative --set paths keep their meaning.
void write_jobs(const ExperimentOptions& o, const std::vector<ExperimentRun>& runs,
                const std::vector<comorph::coopt::CooptConfig>& configs) {
  int cores = 1;
  for (const auto& c : configs) cores = std::max(cores, job_cores(c, o.config));
  const std::string exe = fs::canonical("/proc/self/exe").string();
  const std::string cwd = fs::current_path().string();
  const std::string out = fs::absolute(o.out).lexically_normal().string();
  const std::string seeds = fmt::format("{}", fmt::join(o.seeds, ","));

  std::vector<std::string> lines;
  for (const auto& run : runs) {
    std::vector<std::string> words = {exe, "experiment", "--table", std::to_string(o.table), "--config",
                                      fs::absolute(o.config).lexically_normal().string()};
    for (const auto& s : o.sets) words.insert(words.end(), {"--set", s});
    words.insert(words.end(), {"--out", out, "--only", run.column.name});
    if (run.seed != 0) words.insert(words.end(), {"--seeds", std::to_string(run.seed)});
    if (o.eval_episodes > 0) words.insert(words.end(), {"--eval-episodes", std::to_string(o.eval_episodes)});
    if (o.eval_seed >= 0) words.insert(words.end(), {"--eval-seed", std::to_string(o.eval_seed)});
    words.push_back("--no-table");
    const std::string dir = fs::absolute(run.dir).lexically_normal().string();
    lines.push_back(fmt::format("cd {} && mkdir -p {} && {} >> {} 2>&1", shell_word(cwd), shell_word(dir),
                                command_line(words), shell_word((fs::path(dir) / kJobLogFile).string())));
  }
  std::vector<std::string> collect_words = {exe, "experiment", "--table", std::to_string(o.table), "--out", out};
  if (!o.seeds.empty()) collect_words.insert(collect_words.end(), {"--seeds", seeds});
  collect_words.push_back("--collect");
  const std::string collect_line = command_line(collect_words);
  const int machine = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));

  if (!o.jobs_file.empty()) {
    std::string text;
    for (const auto& l : lines) text += l + "\n";
    comorph::write_file_atomic(o.jobs_file, text);
    std::printf("wrote %s: %zu jobs, %s each; on this machine (%s):\n  parallel -j %d < %s\n",
                o.jobs_file.c_str(), lines.size(), cores_text(cores).c_str(), cores_text(machine).c_str(),
                std::max(1, machine / cores), shell_word(o.jobs_file).c_str());
  }
  if (!o.slurm_file.empty()) {
    const std::string array = fmt::format("0-{}", lines.size() - 1);
    std::string text = fmt::format(
        "#!/bin/bash\n"
        "# comorph experiment, table {}: {} runs (column x seed), one array task each, {} a task;\n"
        "# each task logs to its run directory's {}. Submit (M tasks at once; submitting again\n"
        "# resumes what stopped and skips what finished):\n"
        "#   sbatch --array={}%M {}\n"
        "# then the table and report from what exists:\n"
        "#   {}\n"
        "#SBATCH --job-name=comorph-table-{}\n"
        "#SBATCH --array={}\n"
        "#SBATCH --cpus-per-task={}\n"
        "#SBATCH --output=/dev/null\n"
        "case \"${{SLURM_ARRAY_TASK_ID:?submit this file with sbatch --array}}\" in\n",
        o.table, lines.size(), cores_text(cores), kJobLogFile, array, shell_word(o.slurm_file), collect_line, o.table, array,
        cores);
    for (std::size_t i = 0; i < lines.size(); ++i) text += fmt::format("  {}) {} ;;\n", i, lines[i]);
    text += "  *) echo \"no task $SLURM_ARRAY_TASK_ID in this array (0 to " + std::to_string(lines.size() - 1) +
            ")\" >&2; exit 2 ;;\nesac\n";
    comorph::write_file_atomic(o.slurm_file, text);
    std::printf("wrote %s: %zu array tasks, %s each; submit with\n  sbatch --array=%s%%M %s\n",
                o.slurm_file.c_str(), lines.size(), cores_text(cores).c_str(), array.c_str(),
                shell_word(o.slurm_file).c_str());
  }
  std::printf("then the table and report from what exists:\n  %s\n", collect_line.c_str());
}

}  // namespace

std::vector<int> parse_seeds(const std::string& text) {
  const std::string form = "--seeds takes seeds >= 1 as a list and ranges, e.g. 1-3 or 1,2,5 or 1-3,7";
  auto whole = [&](const std::string& s) {
    if (s.empty() || s.size() > 9 || !std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; }))
      throw std::runtime_error(fmt::format("{}; got '{}'", form, comorph::quote_value(text)));
    const int v = std::stoi(s);
    if (v < 1) throw std::runtime_error(fmt::format("{}; got '{}'", form, comorph::quote_value(text)));
    return v;
  };
  std::vector<int> seeds;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    const std::string part = text.substr(start, comma - start);
    const std::size_t dash = part.find('-');
    const int lo = whole(part.substr(0, dash));
    const int hi = dash == std::string::npos ? lo : whole(part.substr(dash + 1));
    if (hi < lo || hi - lo >= 1000)
      throw std::runtime_error(fmt::format("{}; got '{}'", form, comorph::quote_value(text)));
    for (int s = lo; s <= hi; ++s) seeds.push_back(s);
    start = comma + 1;
  }
  std::sort(seeds.begin(), seeds.end());
  if (std::adjacent_find(seeds.begin(), seeds.end()) != seeds.end())
    throw std::runtime_error(fmt::format("--seeds names a seed twice: '{}'", comorph::quote_value(text)));
  return seeds;
}

bool run_experiment(const ExperimentOptions& o) {
  const bool write_only = !o.jobs_file.empty() || !o.slurm_file.empty();
  if (!o.runs.empty() && !o.collect) throw std::runtime_error("experiment: --runs goes with --collect");
  if (o.collect && (write_only || o.no_table))
    throw std::runtime_error("experiment: --collect trains nothing; drop --jobs, --slurm and --no-table");
  if (!o.collect && o.config.empty())
    throw std::runtime_error("experiment: give --config FILE (only --collect goes without)");
  const auto paper = comorph::report::load_paper_reference(comorph::report::default_paper_reference_path());
  const std::vector<ExperimentRun> runs = selected_runs(o, paper);
  if (o.collect) {
    collect(o, paper);
    return true;
  }
  // Every run's config is checked before hours of training start.
  std::vector<comorph::coopt::CooptConfig> configs;
  for (const auto& r : runs) configs.push_back(comorph::coopt::load_coopt_config(o.config, r.sets));
  if (write_only) {
    write_jobs(o, runs, configs);
    return true;
  }
  fs::create_directories(o.out);

  std::vector<RunTimes> times;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const ExperimentRun& run = runs[i];
    std::fprintf(stderr, "experiment: run %zu/%zu: %s\n", i + 1, runs.size(), run.dir.c_str());
    RunTimes t;
    t.name = fs::path(run.dir).filename().string();
    // One writer per run for its training and its evaluations.
    fs::create_directories(run.dir);
    const comorph::RunLock lock(run.dir);
    if (!train_experiment_run(o, run, configs[i], t)) {
      std::fprintf(stderr, "experiment interrupted in %s (checkpoint written); run the same command again to continue\n",
                   run.dir.c_str());
      return false;
    }
    const auto info = comorph::coopt::read_checkpoint_info(run.dir);
    t.train_wall_s = info.wall_s;
    t.env_steps = static_cast<long long>(info.env_steps);
    for (const auto& scenario : run.column.scenarios) {
      if (fs::exists(fs::path(run.dir) / ("eval-" + scenario + ".json"))) continue;
      const auto start = Clock::now();
      eval_run(run.dir, scenario, o.eval_episodes, o.eval_seed, 0);
      t.eval_wall_s += std::chrono::duration<double>(Clock::now() - start).count();
    }
    comorph::write_file_atomic((fs::path(run.dir) / kFinishedFile).string(),
                               fmt::format("trained {} episodes ({} control steps, {:.0f} s); evaluated on {}\n",
                                           info.episodes, info.env_steps, info.wall_s,
                                           fmt::join(run.column.scenarios, ", ")));
    times.push_back(t);
  }

  std::printf("%-18s %-12s %14s %14s %12s\n", "run", "training", "train wall s", "control steps", "eval wall s");
  double train_total = 0, eval_total = 0;
  for (const auto& t : times) {
    std::printf("%-18s %-12s %14.0f %14lld %12.0f\n", t.name.c_str(), t.training.c_str(), t.train_wall_s, t.env_steps,
                t.eval_wall_s);
    train_total += t.train_wall_s;
    eval_total += t.eval_wall_s;
  }
  std::printf("%-18s %-12s %14.0f %14s %12.0f  (training: all parts of each run; eval: this call only)\n", "total", "",
              train_total, "", eval_total);
  if (!o.no_table) collect(o, paper);
  return true;
}

}  // namespace comorph::workflows
