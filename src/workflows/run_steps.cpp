// train_run / eval_run (run_steps.hpp): what `comorph train`, `eval` and
// `experiment` do to a run directory (docs/report.md: run.yaml, episodes.csv,
// eval-<scenario>.json, plus config.yaml, evaluations.csv and checkpoint/).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <vector>

#include <fmt/format.h>

#include "workflows/run_steps.hpp"
#include "coopt/config.hpp"
#include "coopt/trainer.hpp"
#include "report/episode_record.hpp"
#include "report/metrics.hpp"
#include "common/file_io.hpp"
#include "common/gzip.hpp"
#include "common/run_lock.hpp"

namespace comorph::workflows {
namespace {
namespace fs = std::filesystem;
using comorph::coopt::CooptConfig;
using comorph::coopt::EpisodeLog;

// "0.53", or "-" for NaN (no episode of that kind).
std::string format_rate(double v) { return std::isnan(v) ? std::string("-") : fmt::format("{:.2f}", v); }

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop = true; }

// The report's columns of a log (the base part: EpisodeLog extends the record).
const comorph::report::EpisodeRecord& to_record(const EpisodeLog& l) { return l; }

// F(H) as the env defines it (task/rewards.hpp, env.task.objective in the config).
const comorph::task::ObjectiveWeights& f_weights(const CooptConfig& c) { return c.env.task.objective; }

}  // namespace

namespace {
// What a run directory may hold before its training starts.
bool kept_before_training(const fs::path& entry) {
  return entry.filename() == RunLock::kFileName || entry.filename() == kJobLogFile;
}
}  // namespace

bool is_empty_run_dir(const std::string& dir) {
  if (!fs::exists(dir)) return true;
  if (!fs::is_directory(dir)) return false;
  for (const auto& entry : fs::directory_iterator(dir))
    if (!kept_before_training(entry.path())) return false;
  return true;
}

void clear_run_dir(const std::string& dir) {
  for (const auto& entry : fs::directory_iterator(dir))
    if (!kept_before_training(entry.path())) fs::remove_all(entry.path());
}

void serve_train_actor(const std::string& config_path, const std::vector<std::string>& sets,
                       const std::string& resume) {
  const CooptConfig config = resume.empty()
                                 ? comorph::coopt::load_coopt_config(config_path, sets)
                                 : comorph::coopt::load_coopt_config((fs::path(resume) / "config.yaml").string());
  comorph::coopt::serve_actor_rank(config);
}

bool train_run(const std::string& config_path, const std::vector<std::string>& sets, const std::string& out,
               const std::string& resume, bool locked_by_caller, bool mpi_actors) {
  std::string run_dir;
  CooptConfig config;
  std::unique_ptr<RunLock> lock;  // one writer per run directory, for the whole training
  if (!resume.empty()) {
    if (!config_path.empty() || !sets.empty())
      throw std::runtime_error("--resume takes the run's own config.yaml; drop --config/--set");
    run_dir = resume;
    if (!fs::is_directory(run_dir)) throw std::runtime_error(run_dir + ": no such run directory");
    // Before anything is read: another writer may be in the middle of a checkpoint.
    if (!locked_by_caller) lock = std::make_unique<RunLock>(run_dir);
    const std::string path = (fs::path(run_dir) / "config.yaml").string();
    if (!fs::exists(path)) throw std::runtime_error(run_dir + ": not a training run (no config.yaml)");
    config = comorph::coopt::load_coopt_config(path);
    comorph::coopt::read_checkpoint_info(run_dir);  // throws when there is no checkpoint
  } else {
    if (config_path.empty()) throw std::runtime_error("train: give --config FILE (or --resume runs/NAME)");
    if (out.empty()) throw std::runtime_error("train: give --out runs/NAME");
    config = comorph::coopt::load_coopt_config(config_path, sets);
    if (!is_empty_run_dir(out))
      throw std::runtime_error(out + " exists and is not empty (use --resume " + out + " to continue it)");
    run_dir = out;
  }
  // Everything that can fail on bad input happens before the directory exists.
  comorph::coopt::Trainer trainer(config, run_dir, {},
                                  mpi_actors ? comorph::coopt::ActorPlacement::mpi_ranks
                                             : comorph::coopt::ActorPlacement::threads);

  if (resume.empty()) {
    fs::create_directories(run_dir);
    if (!locked_by_caller) lock = std::make_unique<RunLock>(run_dir);
    // A second `train --out` of the same directory may have passed the check
    // above too; the one that locked first owns it.
    if (!is_empty_run_dir(run_dir))
      throw std::runtime_error(run_dir + " was filled by another process meanwhile; refusing to write into it");
    // trainer.run() writes config.yaml, run.yaml and the CSV headers.
  } else {
    trainer.resume();
    std::fprintf(stderr, "resuming %s after %d episodes (%lld control steps)\n", run_dir.c_str(),
                 trainer.episodes_done(), static_cast<long long>(trainer.env_steps()));
  }

  g_stop = false;
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  const bool finished = trainer.run(&g_stop);
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  const double wall = trainer.wall_s();
  std::fprintf(stderr, "%s %s: %d episodes, %lld control steps, %.0f s wall, %.0f steps/s\n",
               finished ? "finished" : "interrupted, checkpoint written:", run_dir.c_str(), trainer.episodes_done(),
               static_cast<long long>(trainer.env_steps()), wall, wall > 0 ? trainer.env_steps() / wall : 0.0);
  return finished;
}

report::EvalSummary eval_run(const std::string& run_dir, const std::string& scenario, int episodes, int seed,
                         int workers, int forced_modules, bool pilot_drives) {
  const std::string path = (fs::path(run_dir) / "config.yaml").string();
  if (!fs::exists(path)) throw std::runtime_error(run_dir + ": not a training run (no config.yaml)");
  const CooptConfig config = comorph::coopt::load_coopt_config(path);
  comorph::coopt::EvalRequest request;
  request.scenario = scenario;
  request.episodes = episodes > 0 ? episodes : config.eval.episodes;
  request.seed = seed >= 0 ? seed : config.eval.seed;
  request.workers = workers > 0 ? workers : config.eval.workers;
  if (request.workers == 0) request.workers = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  request.forced_modules = forced_modules;
  request.pilot_drives = pilot_drives;
  // A progress line on stderr every 30 s and at the end: 300 episodes take minutes.
  const auto started = std::chrono::steady_clock::now();
  auto last_line = started;
  request.on_episode_finished = [&](int finished, int total) {
    const auto now = std::chrono::steady_clock::now();
    if (finished < total && now - last_line < std::chrono::seconds(30)) return;
    last_line = now;
    const double s = std::chrono::duration<double>(now - started).count();
    std::fprintf(stderr, "eval %s: %d/%d episodes, %.0f s, ETA %.0f s\n", scenario.c_str(), finished, total, s,
                 s / finished * (total - finished));
  };
  const auto logs = comorph::coopt::evaluate(config, run_dir, request);

  std::vector<comorph::report::EpisodeRecord> records;
  for (const auto& l : logs) records.push_back(to_record(l));
  const auto m = comorph::report::summarize(records, f_weights(config), comorph::coopt::stair_heights(config));
  const std::string name =
      "eval-" + scenario + (forced_modules > 0 ? "-modules" + std::to_string(forced_modules) : std::string()) +
      (pilot_drives ? "-pilot" : "");
  const std::string json = (fs::path(run_dir) / (name + ".json")).string();
  const std::string csv = (fs::path(run_dir) / (name + "-episodes.csv")).string();
  comorph::report::write_metrics_json(json, m);
  comorph::report::write_episodes_csv(csv, records);

  std::printf("%s, scenario %s: %d greedy episodes (seeds %d..%d)%s\n", run_dir.c_str(), scenario.c_str(),
              request.episodes, request.seed, request.seed + request.episodes - 1,
              (std::string(forced_modules > 0 ? fmt::format(", forced chain of {} modules", forced_modules) : "") +
               (pilot_drives ? ", driven by the scripted pilot" : ""))
                  .c_str());
  std::printf("%-8s %-9s %s\n", "stairs", "success", "configurations (episodes)");
  for (const std::string& key : comorph::report::stair_keys(m)) {
    std::string seqs;
    if (m.configurations.count(key))
      for (const auto& [seq, n] : m.configurations.at(key)) seqs += (seqs.empty() ? "" : ", ") + seq + " x" + std::to_string(n);
    std::printf("%-8s %-9s %s\n", (key + " m").c_str(), format_rate(m.success_rate.at(key)).c_str(), seqs.c_str());
  }
  std::printf("%-8s %-9s\n", "avg", format_rate(m.success_rate.at("avg")).c_str());
  std::string first;
  for (const std::string& key : comorph::report::stair_keys(m))
    if (m.first_modules.count(key) && !std::isnan(m.first_modules.at(key)))
      first += fmt::format("{}{:.2f} at {} m", first.empty() ? "" : ", ", m.first_modules.at(key), key);
  if (!first.empty())
    std::printf("first configuration, mean modules: %s; after the stairs shed to 2-3 modules: %s of the episodes "
                "that climbed them\n",
                first.c_str(), std::isnan(m.shed_after_stairs) ? "-" : fmt::format("{:.0f} %", 100 * m.shed_after_stairs).c_str());
  std::printf("time %s s, energy %s J (means over successful episodes), F %.3f\n",
              std::isnan(m.time_s) ? "-" : fmt::format("{:.1f}", m.time_s).c_str(),
              std::isnan(m.energy_J) ? "-" : fmt::format("{:.0f}", m.energy_J).c_str(), m.F);
  std::string terms;
  for (const auto& [reason, n] : m.terminations) terms += (terms.empty() ? "" : ", ") + reason + " " + std::to_string(n);
  std::printf("terminations: %s\n", terms.c_str());
  // What the first decision is paid, per stair height: the quantities its
  // choice trades (R2 = summed R1 + the climb reward - sigma3 x stair energy).
  std::printf("first segment (to the first declared switch), means per stair height:\n");
  for (const std::string& key : comorph::report::stair_keys(m)) {
    double r2 = 0, r1 = 0, steps = 0, stairs_J = 0;
    int n = 0;
    for (const auto& l : logs)
      if (comorph::report::stair_key(l.stair_height_m) == key) {
        r2 += l.first_segment_R2;
        r1 += l.first_segment_R1;
        steps += l.first_segment_steps;
        stairs_J += l.stairs_energy_J;
        ++n;
      }
    if (n > 0)
      std::printf("  %s m: R2 %.1f, summed R1 %.1f, %.0f control steps; stair energy E_c %.0f J (%d episodes)\n",
                  key.c_str(), r2 / n, r1 / n, steps / n, stairs_J / n, n);
  }
  std::printf("wrote %s and %s\n", json.c_str(), csv.c_str());
  return m;
}

std::uintmax_t export_run(const std::string& run_dir, const std::string& out) {
  const std::string path = (fs::path(run_dir) / "config.yaml").string();
  if (!fs::exists(path)) throw std::runtime_error(run_dir + ": not a training run (no config.yaml)");
  if (fs::exists(out) && fs::equivalent(out, run_dir)) throw std::runtime_error("export: --out is the run itself");
  const CooptConfig config = comorph::coopt::load_coopt_config(path);
  fs::remove_all(fs::path(out) / "checkpoint");
  fs::create_directories(out);
  std::uintmax_t bytes = comorph::coopt::export_policy(config, run_dir, (fs::path(out) / "checkpoint").string());
  for (const auto& e : fs::directory_iterator(run_dir)) {
    const std::string name = e.path().filename().string();
    // The evaluations' summaries (their per-episode CSVs are made again by `comorph eval`).
    const bool eval_file = name.rfind("eval-", 0) == 0 && e.path().extension() == ".json";
    if (!e.is_regular_file()) continue;
    if (name != "config.yaml" && name != "run.yaml" && name != "episodes.csv" && name != "evaluations.csv" && !eval_file)
      continue;
    fs::path to = fs::path(out) / name;
    if (name == "episodes.csv") {
      // Thousands of rows, rounded to what the report shows (1 ms, 0.1 J,
      // 0.1 of R1, 1e-4) and gzipped: the training log of a 5300-episode run
      // takes ~0.1 MB beside its networks' 1.8 MB (256 x 256), in results/' 2 MB.
      auto records = comorph::report::read_episodes_csv(e.path().string());
      // v rounded to 1 / per_unit: dividing by a whole number gives the double
      // nearest the decimal, which the CSV writer prints in its few digits.
      auto round_to = [](double v, double per_unit) { return std::round(v * per_unit) / per_unit; };
      for (auto& r : records) {
        r.time_s = round_to(r.time_s, 1e3);
        r.energy_J = round_to(r.energy_J, 10);
        r.distance_fraction = round_to(r.distance_fraction, 1e4);
        r.return_R1 = round_to(r.return_R1, 10);
        r.action_saturation = round_to(r.action_saturation, 1e4);
      }
      std::ostringstream text;
      comorph::report::write_episodes_csv(text, records);
      to += ".gz";
      fs::remove(fs::path(out) / name);  // an earlier export's plain log would be read instead
      comorph::write_file_atomic(to.string(), comorph::gzip_compress(text.str()));
    } else {
      fs::copy_file(e.path(), to, fs::copy_options::overwrite_existing);
    }
    bytes += fs::file_size(to);
  }
  std::printf("exported %s to %s: %.2f MB (networks without replay buffers or optimizers)\n", run_dir.c_str(),
              out.c_str(), static_cast<double>(bytes) / 1e6);
  return bytes;
}

}  // namespace comorph::workflows
