// The trainer's simulation threads (trainer.simulation_threads > 1): each owns
// what an episode needs besides the learners (env, scene source, pilot, acting
// copies of both models, random streams), and they step in rounds that the
// trainer's own thread closes. Internal to coopt: trainer.cpp and
// simulation_threads.cpp use it.
//
// A round: every thread with an episode steps until it has done a round's
// simulation work (sync_interval control steps of a 4-module chain; more
// steps with fewer modules) or its episode ends, then waits. The trainer's thread then
// waits for the learner thread's previous job, copies both models' weights
// into every acting copy and hands over the round's transitions (motion
// model) and decisions (configuration model), thread by thread, as the next
// job; it writes the episodes that ended (in index order) and gives their
// threads the next indices. All of it follows the run (steps, module counts), and each
// episode seeds its own random streams, so a (seed, thread count) pair gives
// the same results every time.
// Checkpoints, evaluations and the DQN refit's start fall at block ends, when
// every thread has ended its episode and the learner has caught up.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <exception>
#include <mutex>
#include <random>
#include <thread>
#include <vector>

#include "coopt/episode_runner.hpp"
#include "coopt/learner_worker.hpp"
#include "coopt/trainer.hpp"
#include "task/scripted_pilot.hpp"

namespace comorph::coopt {

// A decision of the configuration model, stored at the round's end.
struct StoredDecision {
  Transition transition;
  int k = 1;  // control steps of its segment (the discount's exponent)
};

struct SimulationThread {
  SimulationThread(const CooptConfig& c, const std::function<int(int, int)>& label_source);

  EpisodeRunner runner;          // env, scene source, observation buffers
  Agent agent;                   // acting copies: motion policy and DQN (config_copy)
  const rl::Learner* config_source = nullptr;  // the DQN its copy was built for (the refit makes a new one)
  std::int64_t config_synced_updates = -1;     // that DQN's updates at the last weight copy
  task::ScriptedPilot pilot;
  std::mt19937_64 rng;           // the episode's uniform configuration choices and pilot noise
  // Hand-over buffers (preallocated): `filling` is written during a round
  // while the learner may still read the other one.
  std::vector<Transition> pending[2];
  int filling = 0;
  int round_steps = 0;           // control steps in the current round
  int stored = 0;                // of those, transitions for the motion learner (none in the refit)
  int round_cost = 0;            // their simulation cost (simulation_threads.cpp: step_cost)
  // The round's decisions for the DQN (and their log rows), in order.
  std::vector<StoredDecision> decisions;
  std::vector<DecisionLog> decision_logs;
  // trainer.config_target: return: this episode's decisions until it ends.
  std::vector<Transition> episode_decisions;
  std::vector<float> episode_decision_returns;

  int episode = -1;              // the training episode it plays; -1: idle (written under Rounds::mutex)
  bool ended = false;            // its episode ended in this round; `log` holds it
  EpisodeLog log;
  Laps laps;                     // this thread's time (TrainerTiming)
  std::uint64_t generation = 0;  // the last release it saw
  std::thread thread;
};

// The rounds' synchronization: threads arrive, the trainer's thread releases
// them by bumping the generation.
struct Rounds {
  std::mutex mutex;
  std::condition_variable cv;
  std::uint64_t generation = 0;
  int arrived = 0;
  bool quit = false;
  std::exception_ptr error;  // the first exception of a simulation thread
  // The learner thread's job: the round's transitions and decisions, thread
  // by thread (rebuilt after the previous job has ended).
  struct Batch {
    const std::vector<Transition>* transitions;
    int count;
  };
  std::vector<Batch> batches;
  std::vector<StoredDecision> decisions;
};

}  // namespace comorph::coopt
