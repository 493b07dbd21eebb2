// The hierarchical co-optimization trainer (paper Fig. 2, Algorithms 1 and 2)
// and the greedy evaluator. No torch in this header (pimpl): the CLI includes it.
//
// Per training episode:
//  1. the configuration model (rl::Dqn over the 9 chains of 2..10 modules)
//     sees the first depth image [+ C_n and the scene] and picks the chain;
//     the env is reset with it (fixed mode: trainer.fixed_modules, no DQN);
//  2. every control step the motion model (rl::Td3 or rl::Sac) acts on depth +
//     state; the motion mode follows the current scene (stairs -> stair mode,
//     else flat); R1 goes to the motion model's replay;
//  3. the switch detector (perception::SwitchDetector on the simulator's
//     labels, or SceneMonitor on the classifier's) declares scene switches; at
//     each switch the segment so far becomes one semi-MDP transition for the
//     DQN (reward R2 of Eq. 7, discount gamma^k, next mask [2, C_n]) and the
//     DQN decides again among [2, C_n] (env.reconfigure sheds tail modules);
//  4. at the episode end the last segment is stored (terminated/truncated).
//
// Inside (coopt/acting.hpp): actors play the episodes with acting copies
// (rl::Policy) of both models and hand their rollouts over as values; a
// learner host holds both learners (the motion learner on a learner thread),
// takes the rollouts in and sends the weights back as bytes. With one actor
// that is one acting thread handing over every trainer.sync_interval control
// steps and at every episode end; with trainer.simulation_threads > 1 the
// actors step in lockstep rounds. The schedule is a function of the run
// only, so the threaded and the inline learner give the same results for a
// seed (docs/coopt.md has the trade-off: the acting policy lags the learner
// by one to two intervals).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "coopt/config.hpp"
#include "task/episode_record.hpp"

namespace comorph::task {
class MultiTaskEnv;  // task/multitask_env.hpp: what a StepObserver sees
}

namespace comorph::coopt {

class LearnerHost;     // coopt/learner_host.hpp
class ActorTransport;  // coopt/acting.hpp

// One finished episode (training or evaluation): the report's episode record
// (task::EpisodeRecord) plus what only the trainer knows.
struct EpisodeLog : task::EpisodeRecord {
  double return_R2 = 0;             // summed R2 over the DQN's segments (Eq. 7); 0 in fixed mode
  double F = 0;                     // F(H) with the task's objective weights
  int steps = 0;                    // control steps
  int switches = 0;                 // scene switches declared by the detector
  double stairs_energy_J = 0;       // E_c: J drawn while on the stairs (the R2 cost)
  // The first configuration's segment (start to the first declared switch, or
  // to the end), also in fixed mode: what the first decision is paid (R2,
  // Eq. 7), how long it lasted and its summed R1. Diagnostics of the choice.
  double first_segment_R2 = 0;
  double first_segment_R1 = 0;
  int first_segment_steps = 0;
  bool warmup = false;              // random-action warm-up episode
};

// One periodic evaluation (a row of evaluations.csv).
struct EvaluationLog {
  int train_episode = 0;            // training episodes done when it ran
  std::int64_t env_steps = 0;       // training control steps done
  double wall_s = 0;                // training wall time, s
  std::vector<EpisodeLog> episodes; // the greedy episodes
};

// One semi-MDP transition of the configuration model (training only).
struct DecisionLog {
  int episode = 0;           // training episode
  int step = 0;              // control step of the episode at which the segment ended
  int modules = 0;           // modules chosen for the segment that just ended
  double r2 = 0;             // reward R2 (Eq. 7) of the segment
  int k = 0;                 // control steps of the segment (discount gamma^k)
  int next_max_modules = 0;  // the next state's mask allows [2, this]
  bool terminated = false;   // the episode ended in a terminal state in this segment
  bool truncated = false;    // the episode hit the step cap in this segment
};

struct TrainerCallbacks {
  std::function<void(const EpisodeLog&)> on_episode;        // after every training episode
  std::function<void(const EvaluationLog&)> on_evaluation;  // after every periodic evaluation
  std::function<void(const DecisionLog&)> on_decision;      // after every stored DQN transition
  // Optional custom labeller for scene_source: ground_truth (tests, other
  // label sources): (control step of the episode, ground-truth label) -> label
  // fed to the switch detector. With MPI actors, give the same to
  // serve_actor_rank on every actor rank.
  std::function<int(int, int)> label_source;
};

// What a checkpoint says about its run (run_dir/checkpoint/trainer.yaml).
struct CheckpointInfo {
  int episodes = 0;             // training episodes done (= rows of episodes.csv)
  int evaluations = 0;          // periodic evaluations done (= rows of evaluations.csv)
  std::int64_t env_steps = 0;   // training control steps done
  double wall_s = 0;            // training wall time so far, s
  std::string config_text;      // the config the run was started with (resolved; merged input before resolving)
  std::string env_text;         // CooptConfig::env_text of the run (the simulator config files)
  std::string directory;        // where it was read from
};
// Reads the latest complete checkpoint of a run whose files match their
// checksums (common/checksum.hpp): checkpoint/, or checkpoint.old/ (said on
// stderr) when checkpoint/ is damaged or missing. Throws naming the damaged
// file when neither is usable, or when there is no checkpoint.
CheckpointInfo read_checkpoint_info(const std::string& run_dir);
// Throws (with the numbers) unless 0 <= episodes <= the config's warm-up +
// training episodes, 0 <= evaluations <= episodes and steps, wall time >= 0.
void check_checkpoint_counts(const CheckpointInfo& info, const CooptConfig& config);
// Throws (naming the first differing line) when the checkpoint was written by
// a config that resolves to other settings, or by another simulator config
// (configs/sim/*.yaml).
void check_same_run(const CheckpointInfo& info, const CooptConfig& config, const std::string& run_dir);
// Keeps the header and the first `rows` data rows of a CSV file (resume after a kill).
void truncate_csv_rows(const std::string& path, int rows);

// Where Trainer::run() spent its wall time, s, for bench/coopt/bench_trainer
// (docs/coopt.md, "Throughput"). Every moment of an actor's thread
// falls in exactly one of its fields (steady_clock laps, no allocation), so
// they add up to about wall_s; motion_updates_s is on the host's thread only without a
// learner thread (trainer.learner_thread: false). learner_busy_s is the time
// the learner spent in its jobs (store + updates), on whichever thread ran them.
// The fields are the mean over the actors (their wait at a round's end in
// waiting_s), with the host's ingesting, inline learning, evaluations,
// checkpoints and logging taken out of that wait into their fields; with
// several actors learner_busy_s holds the DQN's jobs too.
struct TrainerTiming {
  double wall_s = 0;            // run() calls of this object, summed
  double env_step_s = 0;        // MultiTaskEnv::step
  double env_reset_s = 0;       // resets (MJCF built for the chain) and reconfigurations
  double acting_s = 0;          // the motion model's act(), the scripted pilot, building observations
  double handover_s = 0;        // transitions into the hand-over buffer, the policy's count, weight copies
  double waiting_s = 0;         // waiting for the learner's previous job
  double motion_updates_s = 0;  // store + updates run inline (learner_thread: false)
  double dqn_s = 0;             // the configuration model: observation, act, store, updates
  double classifier_s = 0;      // the scene source (switch detector, classifier forward passes)
  double evaluation_s = 0;      // periodic greedy evaluations
  double checkpoint_s = 0;      // writing checkpoints (after waiting for the learner)
  double logging_s = 0;         // callbacks (CSV rows) and progress lines
  double other_s = 0;           // the rest (episode bookkeeping)
  double learner_busy_s = 0;    // the learner's jobs: replay store + gradient updates
  int checkpoints = 0;          // checkpoints written by run()
};

// This process's place in an MPI job that mpirun (OpenMPI) started: joined at
// construction when the job has 2 ranks or more, left at destruction. Rank 0
// trains with the other ranks as its actors (ActorPlacement::mpi_ranks); every
// other rank serves as an actor (serve_actor_rank). Outside mpirun, or with
// one rank, nothing happens.
class MpiJob {
 public:
  MpiJob();
  ~MpiJob();
  MpiJob(const MpiJob&) = delete;
  MpiJob& operator=(const MpiJob&) = delete;
  bool joined() const { return size_ > 1; }
  int rank() const { return rank_; }
  int size() const { return size_; }
  // Ends every rank of the job with `code` (after an error on this one).
  void abort(int code) const;

 private:
  int rank_ = 0, size_ = 1;
};

// Where the trainer's actors run: trainer.simulation_threads threads of this
// process, or the other ranks of the MPI job this process is rank 0 of (one
// actor each; trainer.simulation_threads is then unused). The same seed and
// number of actors give the same results either way.
enum class ActorPlacement { threads, mpi_ranks };

// An actor rank of an MPI job: plays what rank 0's trainer orders until that
// trainer ends the run. `config` must be the run's. `label_source` is
// TrainerCallbacks::label_source: code, not data, so it cannot travel with the
// orders; a program that gives rank 0's trainer one passes the same here on
// every actor rank (the `comorph train` command uses none).
void serve_actor_rank(const CooptConfig& config, const std::function<int(int, int)>& label_source = {});

class Trainer {
 public:
  // run_dir must exist. The trainer writes, through coopt/run_store.hpp,
  // config.yaml, run.yaml, episodes.csv, evaluations.csv and checkpoint/
  // (`comorph eval` adds its files beside them).
  Trainer(const CooptConfig& config, const std::string& run_dir, TrainerCallbacks callbacks = {},
          ActorPlacement actors = ActorPlacement::threads);
  ~Trainer();
  // Loads run_dir's latest checkpoint; throws (naming the difference) when it
  // was written by another configuration. Truncates episodes.csv and
  // evaluations.csv to the rows the checkpoint counted.
  void resume();
  // Trains until every episode is done (returns true) or *stop becomes true
  // (the current episode is finished and checkpointed; returns false; with
  // trainer.simulation_threads > 1 the current block of episodes, which ends
  // at the next multiple of checkpoint_interval or eval_interval). A run
  // not resumed starts by writing config.yaml, run.yaml and the CSV headers
  // (throws when run_dir already holds a run: resume() it instead).
  bool run(const std::atomic<bool>* stop = nullptr);

  int episodes_done() const;
  std::int64_t env_steps() const;
  double wall_s() const;  // training wall time including resumed parts
  TrainerTiming timing() const;

 private:
  std::unique_ptr<LearnerHost> host_;
  std::unique_ptr<ActorTransport> actors_;
};

// Each side of the trainer alone, for bench/coopt/bench_trainer: the acting
// side (the trainer's own training episodes: env, acting copy, pilot, scene
// source, DQN) for at least `steps` control steps without a learner, then the
// motion learner alone (store + the updates the config asks for) on the
// transitions those episodes produced, timed after its learning_starts.
// In control steps per second of wall time; both run on the calling thread.
struct SideRates {
  double acting_steps_per_s = 0;
  double learner_steps_per_s = 0;
  std::int64_t acting_steps = 0;   // control steps the acting side ran (whole episodes)
  std::int64_t learner_steps = 0;  // transitions the timed learner part stored
};
SideRates measure_side_rates(const CooptConfig& config, std::int64_t steps);

// Wall time of two successive Trainer checkpoints into run_dir (which must
// exist): the first after `transitions` transitions were stored in the motion
// learner's replay (and one configuration-model transition per 600 of them,
// about 2.5 decisions per 1500-step episode), the second after `new_transitions` more.
// Random observations: only the sizes matter to the write.
struct CheckpointCost {
  double first_s = 0;
  double next_s = 0;
};
CheckpointCost measure_checkpoint_cost(const CooptConfig& config, const std::string& run_dir,
                                       std::int64_t transitions, std::int64_t new_transitions);

// `comorph eval`: greedy episodes of a trained run on the paper's protocol.
struct EvalRequest {
  std::string scenario = "default";  // a name in task::kScenarios
  int episodes = 30;                 // stair height of episode i = heights[i % 3]
  int seed = 700000;                 // seed of episode i = seed + i
  int workers = 2;                   // threads (each its own env and network copies)
  int forced_modules = 0;            // > 0: the run's motion model drives a fixed chain of this many
                                     // modules (configuration model unused, no shedding): what the
                                     // motion model can do with each body
  // The run's scripted pilot (task::ScriptedPilot as the run's trainer
  // configures it: its gaits and steering, no noise) drives instead of the
  // motion model: the hand-written controller's own figures, beside the
  // learned ones (with forced_modules: each chain).
  bool pilot_drives = false;
  // Called after each finished episode with the number finished so far (one
  // call at a time, from the worker that finished it): progress for the CLI.
  std::function<void(int finished, int episodes)> on_episode_finished;
};
// Loads run_dir/checkpoint; results are ordered by episode and do not depend on `workers`.
std::vector<EpisodeLog> evaluate(const CooptConfig& config, const std::string& run_dir,
                                 const EvalRequest& request);

// Sees the env after the reset that starts control and after every control
// step (`comorph render` records the frames this way). It gets a const env, so
// it cannot change the episode.
using StepObserver = std::function<void(const task::MultiTaskEnv&)>;

// Writes the acting networks of run_dir's checkpoint, without target networks,
// optimizers or replay buffers, to out_checkpoint_dir (motion_actor.pt,
// config_model.pt in hierarchical mode, and trainer.yaml): a checkpoint that
// evaluate(), play_evaluation_episode() and `comorph render` read like the full
// one, but that cannot resume training. Returns the bytes written.
std::uintmax_t export_policy(const CooptConfig& config, const std::string& run_dir,
                             const std::string& out_checkpoint_dir);

// One episode of an evaluation, replayed alone.
struct EvalEpisodeRequest {
  std::string scenario = "default";  // a name in task::kScenarios
  int first_seed = 700000;           // EvalRequest::seed of the evaluation
  int index = 0;                     // episode i: seed first_seed + i, stair height heights[i % 3]
  double stair_height_m = 0;         // > 0: this stair height instead (m)
};
// The same episode as evaluate(config, run_dir, {scenario, ..., first_seed})[index]
// (identical log when stair_height_m is 0), with `observer` (may be empty)
// called along the way. Loads run_dir/checkpoint as evaluate() does.
EpisodeLog play_evaluation_episode(const CooptConfig& config, const std::string& run_dir,
                                   const EvalEpisodeRequest& request, const StepObserver& observer);

// A trained run's acting networks, one observation at a time (the Python
// binding's load_run): loaded from run_dir/checkpoint as evaluate() loads
// them, acting greedily on the inputs play() builds from the env.
class GreedyPolicy {
 public:
  GreedyPolicy(const CooptConfig& config, const std::string& run_dir);
  ~GreedyPolicy();
  bool hierarchical() const;  // has a configuration model
  // Floats of the configuration model's image: the decision camera's
  // (MultiTaskEnv::render_decision_depth) with trainer.decision_camera, else depth().
  int decision_image_size() const;
  // The configuration model's greedy choice of modules in [2, max_modules]
  // for that image, the largest allowed chain C_n and the scene (sim::SceneLabel);
  // target_distance_m (MultiTaskEnv::target_distance) is needed by a run with
  // trainer.config_target_distance and ignored by others.
  int choose_modules(const float* image, int max_modules, int scene, double target_distance_m = -1);
  // The motion model's greedy action (control::kActionSize floats) for the
  // env's depth(), state() and clearance().
  void act(const float* depth, const float* state, const float* clearance, float* action);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace comorph::coopt
