// The run directory as the trainer writes it: everything the trainer writes
// there goes through one RunStore (`comorph eval` adds eval-* files beside). It starts the run (config.yaml, run.yaml and the headers of
// episodes.csv and evaluations.csv; formats in report/), appends their rows,
// writes the checkpoint (checkpoint.tmp, then swapped in, the
// previous one kept as checkpoint.old; replay buffers as segments, checksums
// last), reads it back after checking the run's identity and counts, and cuts
// episodes.csv and evaluations.csv back to the rows the checkpoint counted,
// after checking that those rows are all there.
// Every text file is written atomically (common/file_io.hpp). Internal to coopt;
// the checks it applies are public in coopt/trainer.hpp.
#pragma once

#include <string>

#include "coopt/config.hpp"
#include "coopt/training_state.hpp"
#include "report/metrics.hpp"

namespace comorph::coopt {

// <run_dir>/checkpoint, the latest checkpoint's directory.
std::string checkpoint_dir_of(const std::string& run_dir);

// Loads one checkpoint file into a learner or policy. LibTorch's errors (a C++
// backtrace of 20 lines) become one line naming the file.
void load_learner_file(rl::Learner& learner, const std::string& path);
void load_learner_file(rl::Policy& policy, const std::string& path);

// An evaluation's figures (success per stair height and their average, F(H), ...), as evaluations.csv gives them.
report::EvalSummary evaluation_summary(const CooptConfig& config, const EvaluationLog& evaluation);

class RunStore {
 public:
  explicit RunStore(std::string run_dir) : dir_(std::move(run_dir)) {}
  const std::string& dir() const { return dir_; }
  std::string path(const std::string& name) const;  // a file of the run directory

  // A new run: config.yaml (the resolved config), run.yaml and the headers of
  // episodes.csv and evaluations.csv, into the existing directory; throws when
  // it already holds a run's config.yaml.
  void create(const CooptConfig& config) const;
  // One row of episodes.csv.
  void append_episode(const EpisodeLog& log) const;
  // One row of evaluations.csv; returns the line progress prints for it.
  std::string append_evaluation(const CooptConfig& config, const EvaluationLog& evaluation) const;

  // Writes `s` as the run's checkpoint (the caller has synced both threads);
  // wall_s is the training wall time so far. Updates s's replay segments.
  void save_checkpoint(TrainingState& s, const CooptConfig& config, double wall_s) const;
  // Loads the latest usable checkpoint into `s`; throws (naming the
  // difference; "refusing to resume") when it was written by another config or
  // simulator config or counts impossible numbers, or when episodes.csv or
  // evaluations.csv lacks rows it counts or holds damaged ones. Then cuts the
  // CSV files back to the rows it counts.
  void load_checkpoint(TrainingState& s, const CooptConfig& config) const;

 private:
  void write_checkpoint_files(const TrainingState& s, const CooptConfig& config, double wall_s,
                              const std::string& tmp, rl::ReplaySegments& motion_next,
                              rl::ReplaySegments& config_next) const;
  std::string dir_;
};

}  // namespace comorph::coopt
