// The learner host of the acting protocol (coopt/acting.hpp): both learners
// and the learner thread, the run directory (RunStore), the periodic
// evaluations, the episode rows and progress lines. It hands the actors their
// episodes block by block, takes their rollouts in, and sends back the acting
// weights. act_and_learn() is the one loop that drives a host and a transport.
// Internal to coopt.
#pragma once

#include <array>
#include <atomic>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "coopt/acting.hpp"
#include "coopt/run_store.hpp"
#include "coopt/training_state.hpp"

namespace comorph::coopt {

class LearnerHost {
 public:
  // `actors`: how many the transport has (the schedule: one, or lockstep).
  LearnerHost(const CooptConfig& c, const std::string& run_dir, TrainerCallbacks callbacks, int actors);
  ~LearnerHost();

  const CooptConfig& config() const { return config_; }
  const TrainingState& state() const { return state_; }
  TrainingState& state() { return state_; }
  double wall() const;  // training wall time including resumed parts, s

  // A run not resumed: trainer.refit_motion_from, then config.yaml, run.yaml
  // and the CSV headers.
  void start_run();
  void resume();  // the run directory's latest checkpoint (RunStore::load_checkpoint)

  // A block of episodes: [episode, the next block end) for several actors,
  // one episode for one actor. The DQN refit starts at a block's start.
  void begin_block();
  bool block_active() const { return active_ > 0; }
  const ActingWeights& weights() const { return weights_; }
  const std::vector<Orders>& orders() const { return orders_; }
  // A round's rollouts, by actor: into the learners (through the learner
  // thread), episode rows in index order, the next orders.
  void ingest(std::vector<Rollout*>& rollouts);
  // The learner catches up; then the periodic evaluation and the checkpoint when due.
  void end_block();
  // A checkpoint of everything, after the learner has caught up.
  void checkpoint();

  // measure_side_rates: the motion transitions go into `record`
  // (preallocated) instead of the learner.
  void record_into(std::vector<Transition>* record) { record_ = record; }
  std::size_t recorded() const { return recorded_; }

  Laps laps;  // the host's time (TrainerTiming)
  Clock::duration run_time{};  // run() calls, summed
  TrainerTiming timing(const std::array<Clock::duration, kPhases>& actor_time, int actors) const;

 private:
  Orders start_orders(int episode) const;
  void refresh_motion();  // the learner's acting weights into weights_
  void refresh_config();
  void submit(int transitions, const std::vector<StoredDecision>* decisions);
  void hand_over();  // one actor: the filled interval to the learner thread
  void full_sync();  // the learner caught up, its weights out
  void ingest_one(Rollout& r);
  void ingest_lockstep(std::vector<Rollout*>& rollouts);
  void take_motion_model(const std::string& run_dir);
  // trainer.keep_best_motion: keeps the evaluated motion model when `e` beats
  // the best so far; the refit's start puts the best into the learner.
  void keep_if_best(const EvaluationLog& e);
  void take_best_motion();
  // trainer.motion_average_episodes: the learner's motion model into the running mean; the refit takes the mean.
  void add_motion_snapshot();
  void take_average_motion();
  // The refit's frozen motion model: `kept`'s networks into the learner and the acting copies.
  void take_motion(const rl::Policy& kept);
  void log_episode(const EpisodeLog& log);
  void progress(const EpisodeLog& log);
  EvaluationLog periodic_evaluation();

  CooptConfig config_;
  RunStore store_;
  TrainerCallbacks callbacks_;
  bool one_actor_;
  TrainingState state_;
  EpisodeRunner runner_;  // the periodic evaluations' env and scene source
  std::unique_ptr<LearnerWorker> worker_;
  // The learner thread's input: `filling` is written while the learner may
  // still read the other one.
  std::vector<Transition> pending_[2];
  int filling_ = 0, filled_ = 0;
  std::vector<StoredDecision> job_decisions_;  // lockstep: the round's, stored by the learner thread
  std::vector<Transition>* record_ = nullptr;
  std::size_t recorded_ = 0;

  ActingWeights weights_;
  std::int64_t motion_updates_ = -1, config_updates_ = -1;  // the learners' updates at the last refresh
  std::vector<Orders> orders_;
  std::vector<double> height_weights_;  // the block's stair-height probabilities (trainer.stair_curriculum)
  std::vector<double> pair_weights_;    // ... and (height, first chain) probabilities (trainer.chain_curriculum)
  int next_ = 0, end_ = 0, active_ = 0;  // the block's next index, its end, actors with an episode
  std::map<int, EpisodeLog> ended_;      // episodes that ended before an earlier one: rows go in index order

  Clock::time_point started_ = Clock::now();
  bool run_files_ = false;  // config.yaml, run.yaml and the CSV files exist
  std::vector<double> recent_success_;  // last 20 training episodes
  // wall() at the end of the last episodes (up to 101): the ETA follows the
  // current rate, since a refit episode costs several training episodes.
  std::deque<double> recent_wall_;
  Clock::duration learner_busy_{};  // written by the learner's jobs, read after worker_->wait()
  int run_checkpoints_ = 0;
};

// The one loop: blocks of episodes, round by round, until every episode is
// done (true) or stop() says so at a block's start (false).
bool act_and_learn(LearnerHost& host, ActorTransport& actors, const std::function<bool()>& stop);

}  // namespace comorph::coopt
