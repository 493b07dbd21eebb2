// The acting protocol. Actors play training episodes and hand their rollouts
// over as values (motion transitions, decisions of the configuration model,
// decision and episode logs); the learner host (coopt/learner_host.hpp)
// consumes them and sends back the acting weights as bytes, with each actor's
// orders (its episode, random streams, schedule clocks). One loop drives both
// (act_and_learn, coopt/learner_host.hpp); a transport carries the values
// between them: threads of one process (coopt/actor_threads.hpp), or the
// ranks of an MPI job (coopt/actor_ranks.hpp). Internal to coopt.
//
//   actor i                              learner host
//   ------------------------------       ------------------------------------
//   wait for orders   <-- weights, orders[i] --   round start
//   play until its round ends
//   (or its episode ends)  -- rollout[i] -->      ingest the rollouts in actor
//                                                 order: replay, updates, rows,
//                                                 the ended actors' next episodes
//
// When a round ends follows the run, never the timing (the schedules below),
// so a (seed, number of actors) pair gives the same results on any transport.
// - One actor continues the run's random streams and learns as a single
//   acting thread would: its round ends every trainer.sync_interval motion
//   transitions (the host hands them to the learner thread, which learns while
//   the actor simulates the next interval, and sends the weights its previous
//   job left), at every decision the configuration model learns from (the
//   host learns it at once and sends the new weights; the acting copy's RNG
//   travels with it, so the DQN's acting and sampling draw one stream as
//   before this protocol) and at its episode's end (the host lets the learner
//   catch up).
// - Several actors step in lockstep: a round is the same simulation work
//   for each (step_cost), the host stores the round's transitions and decisions
//   actor by actor as the learner thread's next job, and each episode seeds its
//   own random streams (stream_seed). Checkpoints, evaluations and the DQN
//   refit's start fall at block ends, when every actor has ended its episode.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <random>
#include <vector>

#include "coopt/episode_runner.hpp"
#include "coopt/learner_worker.hpp"
#include "coopt/trainer.hpp"
#include "task/scripted_pilot.hpp"

namespace comorph::coopt {

// What the trainer does in training episode `episode`: everything follows from
// the episode's index, so any actor can play any episode.
struct EpisodePlan {
  bool warmup = false;         // one of the first warmup_episodes
  bool refit = false;          // the DQN refit: motion frozen and greedy, nothing for the motion learner
  bool scripted = false;       // the scripted pilot drives (warm-up, scripted_interval)
  bool greedy_motion = false;  // the motion model acts without exploration noise
  bool config_learns = false;  // the DQN learns from this episode's decisions
  bool random_config = false;  // configurations drawn uniformly (warm-up, pilot_random_configs, random_config_interval)
  bool pilot = false;          // the pilot plans: BC targets, and drives when scripted
  int first_config = -1;       // the first decision's candidate (refit_sweep_scenes, chain_curriculum), else -1
  task::EpisodeSpec spec;      // the scene (seed from trainer.seed and the index)
};
EpisodePlan plan_episode(const TrainerParams& t, int episode);

// The seed of random stream `stream` of training episode `episode` (several
// actors: 0 the actor's RNG, 1 the motion policy's, 2 the DQN copy's; any
// actor count: 3 the stair curriculum's height, 4 whether the chain curriculum
// draws, 5 its pair).
std::uint64_t stream_seed(int seed, int episode, int stream);
// The first episode index after `from` before which every actor must have
// ended its episode: a checkpoint, an evaluation, the refit's start, the end.
int block_end(const TrainerParams& t, int from);
// Several actors: a round's simulation work per actor, and a control step's
// cost with `modules` modules (acting.cpp says why).
int step_cost(int modules);
int round_quota(const TrainerParams& t);

// `n` hand-over transitions of the motion model's sizes (copies into them do not allocate).
void allocate_transitions(const CooptConfig& c, std::vector<Transition>& v, std::size_t n);
// A uniform choice among the mask's valid actions (-1 when none).
int random_valid_action(const std::vector<std::uint8_t>& mask, std::mt19937_64& rng);
DecisionLog decision_log(int episode, int step, const rl::Action& a, float r2, const rl::Observation& next,
                         bool terminated, bool truncated, int k);
// trainer.config_target: return: an ended episode's decisions, with their
// segments' R2 in `r2`, become terminal transitions of the returns (each
// segment's R2 plus the later ones, discounted by gamma once more each); r2 is
// emptied.
void to_return_transitions(std::vector<Transition>& decisions, std::vector<float>& r2, double gamma);
// One transition into a learner, then the updates it asks for.
void store_and_update(rl::Learner& l, const Transition& t, int k = 1);

// A decision of the configuration model for its learner.
struct StoredDecision {
  Transition transition;
  int k = 1;  // control steps of its segment (the discount's exponent)
};

// Actor -> host, at the end of each of the actor's rounds.
struct Rollout {
  std::vector<Transition> transitions;     // preallocated: the first `stored` are the round's
  int stored = 0;
  int steps = 0;                           // control steps of the round
  std::vector<StoredDecision> decisions;   // for the configuration model, in order
  std::vector<DecisionLog> decision_logs;  // their rows (TrainerCallbacks::on_decision)
  bool ended = false;                      // its episode ended with this round: `log`
  EpisodeLog log;
  // The acting side's random streams and the motion policy's clock as they
  // are now: one actor's host keeps them (checkpoints, the next episode).
  std::mt19937_64 rng, motion_rng, config_rng;
  rl::LearnerCounters motion_counters;
  // The actor's time so far (its Laps): a transport between processes
  // reports it from here (TrainerTiming).
  std::array<Clock::duration, kPhases> actor_time{};
  void clear() {
    stored = steps = 0;
    decisions.clear();
    decision_logs.clear();
    ended = false;
  }
};

// Host -> every actor, each round: the acting weights as bytes
// (rl::acting_weights), each with a version that changes when they do.
struct ActingWeights {
  std::uint64_t motion_version = 0;
  std::vector<float> motion;
  std::uint64_t config_version = 0;
  bool config_refit = false;            // the refit's DQN (its own hyperparameters)
  std::vector<float> config;
  rl::LearnerCounters config_counters;  // its epsilon's clock
};

// Host -> one actor, each round.
struct Orders {
  int episode = -1;  // the training episode it plays; -1: none until the next block
  bool start = false;  // `episode` starts now, with these streams:
  std::mt19937_64 rng, motion_rng;
  bool set_motion_counters = false;  // the motion policy's schedule clock
  rl::LearnerCounters motion_counters;
  bool set_config_rng = false;  // the DQN copy's RNG
  std::mt19937_64 config_rng;
  double stair_height_m = 0;  // with `start`: > 0 the episode's stair height (trainer.stair/chain_curriculum)
  int first_config = -1;      // with `start`: >= 0 the first decision's candidate (trainer.chain_curriculum)
};

// The values as bytes, for a transport between processes (coopt/actor_ranks.hpp).
// Reading into a value of the same run's sizes allocates nothing for its
// transitions (Rollout::transitions preallocated) and weights.
void rollout_to_bytes(const Rollout& r, std::vector<char>& bytes);
void rollout_from_bytes(const std::vector<char>& bytes, Rollout& r);
// Without motion_weights (config_weights) the motion (config) weights go as
// an empty buffer: for an actor that holds their version already.
void release_to_bytes(const ActingWeights& w, const Orders& o, bool motion_weights, bool config_weights,
                      std::vector<char>& bytes);
void release_from_bytes(const std::vector<char>& bytes, ActingWeights& w, Orders& o);

// The most transitions one round of one actor can hand over: an interval
// with one actor; in lockstep the quota in steps of the shortest chain, and
// the n - 1 an n-step return held back from the round before.
int most_round_transitions(const TrainerParams& t, int actors);

// Thrown by an ActorLink when the host ends the run.
struct ActorStopped {};

// An actor's side of a transport.
class ActorLink {
 public:
  virtual ~ActorLink() = default;
  // Hands `rollout` over (nullptr: the actor had no episode and arrives with
  // nothing; the host may move out of it) and waits for the next round's
  // weights and orders, which stay valid until the next exchange. Throws
  // ActorStopped when the run ends.
  virtual void exchange(Rollout* rollout, const ActingWeights*& weights, const Orders*& orders) = 0;
};

// The host's side of a transport.
class ActorTransport {
 public:
  virtual ~ActorTransport() = default;
  virtual int actors() const = 0;
  // One round: actor i gets `weights` and orders[i]; each actor with an
  // episode plays until its round ends and hands its rollout over. Returns
  // the rollouts by actor (those of actors without an episode are empty).
  virtual std::vector<Rollout*>& round(const ActingWeights& weights, const std::vector<Orders>& orders) = 0;
  // The actors' time so far, summed over actors (TrainerTiming).
  virtual std::array<Clock::duration, kPhases> actor_time() const = 0;
};

// Everything an episode needs besides the learners: env, scene source, pilot,
// acting copies of both models, random streams, its rollout buffers.
class Actor {
 public:
  // `actors`: how many the run has (the schedule: one, or lockstep).
  Actor(const CooptConfig& c, int actors, const std::function<int(int, int)>& label_source);
  // Plays what the orders say until the host ends the run (ActorStopped).
  void serve(ActorLink& link);
  Laps laps;  // this actor's time (TrainerTiming)

 private:
  void take(const ActingWeights& weights, const Orders& orders);
  void hand_over(ActorLink& link);  // the round's end inside an episode
  void play(int episode, ActorLink& link);

  const CooptConfig& config_;
  bool one_actor_;
  EpisodeRunner runner_;
  Agent agent_;
  std::unique_ptr<rl::Policy> other_config_;  // the DQN copy of the other kind (main or refit)
  bool config_refit_ = false;
  std::uint64_t motion_version_ = 0, config_version_ = 0;
  task::ScriptedPilot pilot_;
  std::mt19937_64 rng_;  // the episode's uniform configuration choices and pilot noise
  double stair_height_m_ = 0;  // > 0: the host's stair height for the episode
  int first_config_ = -1;      // >= 0: the host's first decision for the episode
  task::R2Params training_r2_;  // the R2 the DQN learns from before the refit (trainer.config_energy_weight)
  Rollout rollout_;
  int interval_ = 0;    // one actor: motion transitions since the learner's last hand-over
  int round_cost_ = 0;  // lockstep: the round's simulation work so far
  // trainer.config_target: return: this episode's decisions until it ends.
  std::vector<Transition> episode_decisions_;
  std::vector<float> episode_decision_returns_;
};

}  // namespace comorph::coopt
