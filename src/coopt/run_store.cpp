#include "coopt/run_store.hpp"

#include <torch/torch.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <cmath>
#include <map>
#include <sstream>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "common/checksum.hpp"
#include "common/file_io.hpp"
#include "report/episode_record.hpp"
#include "report/metrics.hpp"
#include "report/run_dir.hpp"
#include "rl/learner.hpp"
#include "rl/policy.hpp"
#include "rl/replay_buffer.hpp"

namespace comorph::coopt {
namespace fs = std::filesystem;
namespace {

template <class Model>
void load_file(Model& model, const std::string& path) {
  try {
    model.load(path);
  } catch (const c10::Error& e) {
    const std::string what = e.what_without_backtrace();
    throw std::runtime_error(path + ": cannot load: " + quote_value(what.substr(0, what.find('\n')), 200));
  }
}

// A learner's replay from its checkpoint's segments (rl/replay_segments.hpp).
// Every transition the learner counts must be back: a missing index would
// otherwise resume with an empty buffer.
rl::ReplaySegments load_replay(rl::Learner& learner, const std::string& name, const std::string& dir) {
  rl::ReplaySegments segments = rl::read_replay_segments(learner.replay(), name, dir);
  const rl::ReplayBuffer& replay = learner.replay();
  const std::int64_t expected = std::min(learner.counters().transitions, replay.capacity());
  if (replay.size() != expected)
    throw std::runtime_error((fs::path(dir) / rl::replay_index_name(name)).string() + ": the replay holds " +
                             std::to_string(replay.size()) + " transitions, the learner stored " +
                             std::to_string(learner.counters().transitions) + " (capacity " +
                             std::to_string(replay.capacity()) + ")");
  return segments;
}

std::string first_difference(const std::string& a, const std::string& b) {
  std::istringstream sa(a), sb(b);
  std::string la, lb;
  int line = 0;
  while (true) {
    const bool ga = static_cast<bool>(std::getline(sa, la));
    const bool gb = static_cast<bool>(std::getline(sb, lb));
    ++line;
    if (!ga && !gb) return "";
    if (!ga || !gb || la != lb)
      return "line " + std::to_string(line) + ": checkpoint has '" + quote_value(gb ? lb : "<end>") +
             "', config has '" + quote_value(ga ? la : "<end>") + "'";
  }
}

// The header of evaluations.csv: a success column per stair height of the run.
std::string evaluation_columns(const CooptConfig& config) {
  std::string columns = "train_episode,env_steps,wall_s,episodes";
  for (const double h : stair_heights(config)) columns += ",success_" + report::stair_key(h);
  return columns + ",success_avg,mean_return_R1,mean_distance_fraction,mean_F,configurations";
}

// "0.53", or "-" for NaN (no episode of that kind).
std::string format_rate(double v) { return std::isnan(v) ? std::string("-") : fmt::format("{:.2f}", v); }

// Data lines of a CSV file after its header (a missing file has none).
std::vector<std::string> csv_data_lines(const std::string& path, std::string& header) {
  std::vector<std::string> lines;
  if (!fs::exists(path)) return lines;
  std::istringstream in(read_text_file(path, report::kMaxRunLogBytes));
  std::getline(in, header);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// Resume continues episodes.csv and evaluations.csv after the rows the
// checkpoint counts (later rows come from after it and are dropped). Those
// rows must all be there and be rows of these files: a shorter file would
// leave a permanent gap, a garbled one would be kept and appended to.
void check_rows_for_resume(const std::string& episodes_csv, const std::string& evaluations_csv,
                           const CheckpointInfo& checkpoint, const std::string& columns) {
  std::string header;
  const auto episodes = csv_data_lines(episodes_csv, header);
  if (static_cast<int>(episodes.size()) < checkpoint.episodes)
    throw std::runtime_error(fmt::format(
        "{}: {} rows, but the checkpoint ({}) counts {} episodes; refusing to resume with a gap", episodes_csv,
        episodes.size(), checkpoint.directory, checkpoint.episodes));
  std::string kept = header + "\n";
  for (int i = 0; i < checkpoint.episodes; ++i) kept += episodes[static_cast<std::size_t>(i)] + "\n";
  std::istringstream rows(kept);
  std::vector<report::EpisodeRecord> records;
  try {
    records = report::read_episodes_csv(rows, episodes_csv);
  } catch (const std::exception& e) {
    throw std::runtime_error(std::string(e.what()) + "; refusing to resume from a damaged episodes.csv");
  }
  for (int i = 0; i < checkpoint.episodes; ++i)
    if (records[static_cast<std::size_t>(i)].episode != i)
      throw std::runtime_error(fmt::format("{}:{}: episode {} where episode {} belongs; refusing to resume",
                                           episodes_csv, i + 2, records[static_cast<std::size_t>(i)].episode, i));

  const auto evaluations = csv_data_lines(evaluations_csv, header);
  if (checkpoint.evaluations > 0 && header != columns)
    throw std::runtime_error(evaluations_csv + ":1: not the header of evaluations.csv; refusing to resume");
  if (static_cast<int>(evaluations.size()) < checkpoint.evaluations)
    throw std::runtime_error(fmt::format(
        "{}: {} rows, but the checkpoint ({}) counts {} evaluations; refusing to resume with a gap",
        evaluations_csv, evaluations.size(), checkpoint.directory, checkpoint.evaluations));
  const auto fields = std::count(columns.begin(), columns.end(), ',') + 1;
  for (int i = 0; i < checkpoint.evaluations; ++i) {
    const std::string& row = evaluations[static_cast<std::size_t>(i)];
    if (std::count(row.begin(), row.end(), ',') + 1 != fields || row.empty() ||
        row.find_first_not_of("0123456789") != row.find(','))
      throw std::runtime_error(fmt::format("{}:{}: not a row of evaluations.csv ('{}'); refusing to resume",
                                           evaluations_csv, i + 2, quote_value(row)));
  }
}

}  // namespace

std::string checkpoint_dir_of(const std::string& run) { return (fs::path(run) / "checkpoint").string(); }

void load_learner_file(rl::Learner& learner, const std::string& path) { load_file(learner, path); }
void load_learner_file(rl::Policy& policy, const std::string& path) { load_file(policy, path); }

// ---------------------------------------------------------------------------

CheckpointInfo read_checkpoint_info(const std::string& run_dir) {
  // checkpoint/ is the newest; checkpoint.old/ the one before it (and the only
  // one after a crash between the two renames of save_checkpoint). The first
  // whose files all match their checksums is used; a damaged one is named.
  std::string dir, problems;
  for (const std::string& candidate : {checkpoint_dir_of(run_dir), checkpoint_dir_of(run_dir) + ".old"}) {
    if (!fs::exists(candidate)) continue;
    std::string problem;
    if (!fs::exists(fs::path(candidate) / "trainer.yaml")) {
      problem = candidate + ": incomplete (no trainer.yaml)";
    } else {
      problem = verify_checksums(candidate);
    }
    if (problem.empty()) {
      dir = candidate;
      break;
    }
    problems += (problems.empty() ? "" : "; ") + problem;
  }
  if (dir.empty())
    throw std::runtime_error(problems.empty() ? run_dir + ": no checkpoint (expected " + checkpoint_dir_of(run_dir) + ")"
                                              : problems + "; no usable checkpoint in " + run_dir);
  if (!problems.empty()) std::fprintf(stderr, "comorph: %s; using the previous checkpoint %s\n", problems.c_str(), dir.c_str());
  const std::string path = (fs::path(dir) / "trainer.yaml").string();
  CheckpointInfo info;
  try {
    const YAML::Node n = load_yaml_file(path);
    info.episodes = n["episodes"].as<int>();
    info.evaluations = n["evaluations"].as<int>();
    info.env_steps = n["env_steps"].as<std::int64_t>();
    info.wall_s = n["wall_s"].as<double>();
    info.config_text = n["config"].as<std::string>();
    info.env_text = n["env_files"].as<std::string>();
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(path + ": unreadable checkpoint: " + e.msg);
  }
  info.directory = dir;
  return info;
}

void check_checkpoint_counts(const CheckpointInfo& info, const CooptConfig& config) {
  const int total = config.trainer.total_episodes();
  if (info.episodes < 0 || info.episodes > total)
    throw std::runtime_error(info.directory + ": the checkpoint counts " + std::to_string(info.episodes) +
                             " episodes, the config has " + std::to_string(total) +
                             " (warm-up + training + DQN refit); refusing to resume");
  if (info.evaluations < 0 || info.evaluations > info.episodes)
    throw std::runtime_error(info.directory + ": the checkpoint counts " + std::to_string(info.evaluations) +
                             " evaluations after " + std::to_string(info.episodes) +
                             " episodes; refusing to resume");
  if (info.env_steps < 0 || info.wall_s < 0)
    throw std::runtime_error(info.directory + ": the checkpoint counts " + std::to_string(info.env_steps) +
                             " control steps and " + std::to_string(info.wall_s) + " s; refusing to resume");
}

void check_same_run(const CheckpointInfo& info, const CooptConfig& config, const std::string& run_dir) {
  if (info.env_text != config.env_text)
    throw std::runtime_error(run_dir + ": the simulator config (" + config.env_dir +
                             ") changed since the checkpoint was written (" +
                             first_difference(config.env_text, info.env_text) + ")");
  // Checkpoints hold the resolved config; those written before configs were
  // resolved hold the merged input, which resolves to the same settings.
  const std::string checkpoint_config =
      info.config_text == config.text
          ? info.config_text
          : coopt_config_from_text(info.config_text, (fs::path(info.directory) / "trainer.yaml").string()).text;
  if (checkpoint_config != config.text)
    throw std::runtime_error(run_dir + ": the checkpoint was written by another configuration (" +
                             first_difference(config.text, checkpoint_config) + ")");
}

void truncate_csv_rows(const std::string& path, int rows) {
  if (!fs::exists(path)) return;
  std::ifstream in(path);
  std::string text, line;
  int kept = -1;  // the header is row -1
  while (kept < rows && std::getline(in, line)) {
    text += line + "\n";
    ++kept;
  }
  in.close();
  write_file_atomic(path, text);
}

std::string RunStore::path(const std::string& name) const { return (fs::path(dir_) / name).string(); }

void RunStore::create(const CooptConfig& config) const {
  // A Trainer run() without resume() on a finished or interrupted run would
  // otherwise start its CSV files and checkpoint over.
  if (fs::exists(path("config.yaml")))
    throw std::runtime_error(dir_ + ": already holds a run (config.yaml); resume it instead of starting it again");
  write_file_atomic(path("config.yaml"), "# The run's resolved config: every setting, defaults included (comorph config keys).\n" +
                                           config.text + "\n");
  report::RunInfo info;
  info.name = fs::path(dir_).filename().string();
  info.kind = name_of(config.trainer.mode);
  info.modules = config.trainer.mode == TrainerMode::fixed ? config.trainer.fixed_modules : kMaxModules;
  info.algo = config.trainer.motion_algo;
  info.scenario = name_of(config.trainer.scenario);
  info.episodes = config.trainer.total_episodes();
  info.preset = config.preset;
  info.notes = "scene source: " + name_of(config.trainer.scene_source);
  report::write_run_info(path("run.yaml"), info);
  report::write_episodes_csv(path("episodes.csv"), {});
  write_file_atomic(path("evaluations.csv"), evaluation_columns(config) + "\n");
}

void RunStore::append_episode(const EpisodeLog& log) const {
  std::ostringstream s;
  report::write_episodes_csv(s, {static_cast<const report::EpisodeRecord&>(log)});
  const std::string text = s.str();
  append_file(path("episodes.csv"), text.substr(text.find('\n') + 1));  // the row without the header
}

report::EvalSummary evaluation_summary(const CooptConfig& config, const EvaluationLog& evaluation) {
  const std::vector<report::EpisodeRecord> records(evaluation.episodes.begin(), evaluation.episodes.end());
  return report::summarize(records, config.env.task.objective, stair_heights(config));
}

std::string RunStore::append_evaluation(const CooptConfig& config, const EvaluationLog& e) const {
  double ret = 0, dist = 0;
  for (const auto& l : e.episodes) {
    ret += l.return_R1;
    dist += l.distance_fraction;
  }
  const report::EvalSummary m = evaluation_summary(config, e);
  const double n = static_cast<double>(e.episodes.size());
  std::string configs;  // "0.04:4x2|6->2x1 0.06:..."
  for (const auto& [height, seqs] : m.configurations) {
    configs += (configs.empty() ? "" : " ") + height + ":";
    bool first = true;
    for (const auto& [seq, count] : seqs) {
      configs += (first ? "" : "|") + seq + "x" + std::to_string(count);
      first = false;
    }
  }
  std::vector<std::string> heights, rates;  // in the order of the run's heights
  for (const double h : stair_heights(config)) {
    heights.push_back(report::stair_key(h));
    rates.push_back(format_rate(m.success_rate.at(heights.back())));
  }
  const std::string avg = format_rate(m.success_rate.at("avg"));
  append_file(path("evaluations.csv"),
              fmt::format("{},{},{:.1f},{},{},{},{:.2f},{:.3f},{:.3f},{}\n", e.train_episode, e.env_steps, e.wall_s,
                          e.episodes.size(), fmt::join(rates, ","), avg, ret / n, dist / n, m.F, configs));
  return fmt::format(
      "evaluation after {} episodes: success {} m = {} (avg {}), return {:.1f}, distance {:.0f} %, configurations {}",
      e.train_episode, fmt::join(heights, "/"), fmt::join(rates, "/"), avg, ret / n, 100.0 * dist / n, configs);
}

void RunStore::save_checkpoint(TrainingState& s, const CooptConfig& config, double wall_s) const {
  const std::string dir = checkpoint_dir_of(dir_);
  const std::string tmp = dir + ".tmp", old = dir + ".old";
  fs::remove_all(tmp);
  fs::create_directories(tmp);
  rl::ReplaySegments motion_next, config_next;
  try {
    write_checkpoint_files(s, config, wall_s, tmp, motion_next, config_next);
  } catch (...) {
    // A full disk: the last good checkpoint stays; free what the partial one took.
    std::error_code ignored;
    fs::remove_all(tmp, ignored);
    try {
      throw;
    } catch (const c10::Error& e) {  // any other LibTorch failure: one line, no backtrace
      const std::string what = e.what_without_backtrace();
      throw std::runtime_error("cannot write the checkpoint " + tmp + ": " + what.substr(0, what.find('\n')));
    }
  }
  // Swap directories: a crash at any point leaves either `checkpoint` or
  // `checkpoint.old` complete (read_checkpoint_info falls back to .old).
  // checkpoint.old stays as the fallback when `checkpoint` is found damaged.
  // The replay segments live in each directory that needs them (hard
  // links), so removing checkpoint.old takes nothing from the others.
  fs::remove_all(old);
  if (fs::exists(dir)) fs::rename(dir, old);
  fs::rename(tmp, dir);
  s.motion_segments = motion_next;
  s.motion_segments.directory = dir;
  s.config_segments = config_next;
  s.config_segments.directory = dir;
}

// The files of a checkpoint into `tmp`, the checksums last. The replay
// buffers go apart from their learners, as segments: only the transitions
// added since the last checkpoint are written (rl/replay_segments.hpp).
void RunStore::write_checkpoint_files(const TrainingState& s, const CooptConfig& config, double wall_s,
                                      const std::string& tmp, rl::ReplaySegments& motion_next,
                                      rl::ReplaySegments& config_next) const {
  std::vector<std::string> files{"motion.pt", "motion_actor.pt", "trainer.yaml"};
  std::map<std::string, std::string> sums;  // of linked segments, known without reading them
  if (s.motion_on_policy) {  // no replay: its rollout is in its own file
    s.motion->save((fs::path(tmp) / "motion.pt").string());
  } else {
    s.motion->save_without_replay((fs::path(tmp) / "motion.pt").string());
    motion_next = rl::write_replay_segments(s.motion->replay(), "motion", tmp, s.motion_segments, files, sums);
  }
  s.agent.motion->save((fs::path(tmp) / "motion_actor.pt").string());  // the acting side: networks, counters, RNG
  if (s.best_motion) {
    s.best_motion->save((fs::path(tmp) / "best_motion_actor.pt").string());
    files.push_back("best_motion_actor.pt");
  }
  if (s.motion_average) {
    s.motion_average->save((fs::path(tmp) / "average_motion_actor.pt").string());
    files.push_back("average_motion_actor.pt");
  }
  if (s.config) {
    s.config->save_without_replay((fs::path(tmp) / "config_model.pt").string());
    files.push_back("config_model.pt");
    config_next = rl::write_replay_segments(s.config->replay(), "config_model", tmp, s.config_segments, files, sums);
  }
  YAML::Emitter e;
  e << YAML::BeginMap;
  e << YAML::Key << "episodes" << YAML::Value << s.episode;
  e << YAML::Key << "evaluations" << YAML::Value << s.evaluations;
  e << YAML::Key << "env_steps" << YAML::Value << s.steps;
  e << YAML::Key << "wall_s" << YAML::Value << wall_s;
  e << YAML::Key << "rng" << YAML::Value << rl::rng_state(s.rng);
  e << YAML::Key << "stair_curriculum" << YAML::Value << s.curriculum.outcomes_text();
  e << YAML::Key << "chain_curriculum" << YAML::Value << s.chain_curriculum.outcomes_text();
  if (s.best_motion) {  // the score exactly (shortest round trip), so a resumed run compares as the uninterrupted one
    e << YAML::Key << "best_motion" << YAML::Value << YAML::BeginMap;
    e << YAML::Key << "episode" << YAML::Value << s.best_motion_episode;
    e << YAML::Key << "success" << YAML::Value << fmt::format("{}", s.best_motion_success);
    e << YAML::Key << "F" << YAML::Value << fmt::format("{}", s.best_motion_F);
    e << YAML::EndMap;
  }
  if (s.motion_average) e << YAML::Key << "motion_average_snapshots" << YAML::Value << s.motion_average_snapshots;
  // env_files ends with a newline, which a literal block keeps; config has
  // none, which only the last value of the document keeps.
  e << YAML::Key << "env_files" << YAML::Value << YAML::Literal << config.env_text;
  e << YAML::Key << "config" << YAML::Value << YAML::Literal << config.text;
  e << YAML::EndMap;
  write_file_atomic((fs::path(tmp) / "trainer.yaml").string(), e.c_str());
  write_checksums(tmp, files, sums);
}

void RunStore::load_checkpoint(TrainingState& s, const CooptConfig& config) const {
  const CheckpointInfo info = read_checkpoint_info(dir_);
  try {
    check_same_run(info, config, dir_);
    check_checkpoint_counts(info, config);
  } catch (const std::exception& e) {
    throw std::runtime_error(std::string(e.what()) + "; refusing to resume");
  }
  check_rows_for_resume(path("episodes.csv"), path("evaluations.csv"), info, evaluation_columns(config));
  load_learner_file(*s.motion, (fs::path(info.directory) / "motion.pt").string());
  if (!s.motion_on_policy) s.motion_segments = load_replay(*s.motion, "motion", info.directory);
  load_learner_file(*s.agent.motion, (fs::path(info.directory) / "motion_actor.pt").string());
  if (s.config) {
    // Inside the DQN refit the checkpoint holds the refit DQN: built with its own hyperparameters.
    if (config.trainer.holds_refit_dqn(info.episodes)) s.start_refit(config);
    load_learner_file(*s.config, (fs::path(info.directory) / "config_model.pt").string());
    s.config_segments = load_replay(*s.config, "config_model", info.directory);
  }
  const YAML::Node n = load_yaml_file((fs::path(info.directory) / "trainer.yaml").string());
  rl::set_rng_state(s.rng, n["rng"].as<std::string>());
  // Checkpoints without one were written before that curriculum existed: it had no outcomes.
  auto outcomes = [&](const char* key, auto& curriculum) {
    if (!n[key]) return;
    try {
      curriculum.set_outcomes_text(n[key].as<std::string>());
    } catch (const std::exception& e) {
      throw std::runtime_error(info.directory + "/trainer.yaml: " + key + ": " + e.what() + "; refusing to resume");
    }
  };
  outcomes("stair_curriculum", s.curriculum);
  outcomes("chain_curriculum", s.chain_curriculum);
  if (const YAML::Node best = n["best_motion"]) {
    try {
      s.best_motion_episode = best["episode"].as<int>();
      s.best_motion_success = best["success"].as<double>();
      s.best_motion_F = best["F"].as<double>();
    } catch (const YAML::Exception& e) {
      throw std::runtime_error(info.directory + "/trainer.yaml: best_motion: " + e.msg + "; refusing to resume");
    }
    s.best_motion = make_motion_policy(config, 0);
    load_learner_file(*s.best_motion, (fs::path(info.directory) / "best_motion_actor.pt").string());
  }
  if (const YAML::Node snapshots = n["motion_average_snapshots"]) {
    try {
      s.motion_average_snapshots = snapshots.as<int>();
    } catch (const YAML::Exception& e) {
      throw std::runtime_error(info.directory + "/trainer.yaml: motion_average_snapshots: " + e.msg +
                               "; refusing to resume");
    }
    s.motion_average = make_motion_policy(config, 0);
    load_learner_file(*s.motion_average, (fs::path(info.directory) / "average_motion_actor.pt").string());
  }
  s.episode = info.episodes;
  s.evaluations = info.evaluations;
  s.steps = info.env_steps;
  s.wall_before = info.wall_s;
  truncate_csv_rows(path("episodes.csv"), s.episode);
  truncate_csv_rows(path("evaluations.csv"), s.evaluations);
}

}  // namespace comorph::coopt
