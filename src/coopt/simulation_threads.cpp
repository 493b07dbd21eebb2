// The trainer with several simulation threads (trainer.simulation_threads > 1;
// coopt/simulation_threads.hpp says how a round goes).
#include "coopt/simulation_threads.hpp"

#include <torch/torch.h>

#include <algorithm>
#include <cstdio>
#include <map>

#include "coopt/segment.hpp"
#include "coopt/trainer_impl.hpp"
#include "coopt/training_state.hpp"
#include "rl/learner.hpp"
#include "rl/policy.hpp"

namespace comorph::coopt {
namespace {

// Thrown inside a simulation thread when the trainer stops the threads.
struct ThreadsStopped {};

// The seed of random stream `stream` of training episode `episode`
// (splitmix64's finalizer: nearby indices give unrelated seeds).
std::uint64_t stream_seed(int seed, int episode, int stream) {
  std::uint64_t z = (static_cast<std::uint64_t>(seed) * 1000003ULL + static_cast<std::uint64_t>(episode)) * 4ULL +
                    static_cast<std::uint64_t>(stream) + 0x9E3779B97F4A7C15ULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

// The first episode index after `from` before which every thread must have
// ended its episode: a checkpoint, an evaluation, the refit's start, the end.
int block_end(const TrainerParams& t, int from) {
  auto next_multiple = [from](int k) { return (from / k + 1) * k; };
  int end = std::min(t.total_episodes(), next_multiple(t.checkpoint_interval));
  if (t.eval_interval > 0) end = std::min(end, next_multiple(t.eval_interval));
  if (from < t.refit_start()) end = std::min(end, t.refit_start());
  return end;
}

// A round gives every thread the same simulation work, not the same steps:
// a control step costs about 60 + 128 us per module (bench_sim: 301 us for 2
// modules, 1338 for 10), so with equal steps a thread with 3 modules would
// wait for one with 9 most of the round. In units of 64 us: 2 per module + 1.
// A round is worth sync_interval steps of a 4-module chain; a thread with 2
// modules takes 1.8 times as many, one with 10 0.43 times. Module counts are
// part of the run, so this too follows the run and not the timing.
int step_cost(int modules) { return 2 * modules + 1; }
int round_quota(const TrainerParams& t) { return t.sync_interval * step_cost(4); }

// A simulation thread waits for the trainer's next release (after arriving:
// its round is done); returns the episode it is to play, -1 when idle.
int await_release(Rounds& r, SimulationThread& s, bool arrive) {
  s.laps.lap(kHandover);
  std::unique_lock<std::mutex> lock(r.mutex);
  if (arrive) {
    ++r.arrived;
    r.cv.notify_all();
  }
  r.cv.wait(lock, [&] { return r.generation != s.generation || r.quit; });
  if (r.quit) throw ThreadsStopped{};
  s.generation = r.generation;
  const int episode = s.episode;
  lock.unlock();
  s.laps.lap(kWaiting);
  return episode;
}

}  // namespace

SimulationThread::SimulationThread(const CooptConfig& c, const std::function<int(int, int)>& label_source)
    : runner(c, label_source) {
  agent.motion = make_motion_policy(c, static_cast<std::uint64_t>(c.trainer.seed) + 1);
  configure_pilot(c.trainer, pilot);
  // The most transitions a round can hold: its quota in steps of the shortest
  // chain, and the n - 1 an n-step return held back from the round before.
  const int most = (round_quota(c.trainer) + step_cost(kMinModules) - 1) / step_cost(kMinModules) +
                   c.trainer.motion_n_step - 1;
  for (auto& p : pending) allocate_transitions(c, p, static_cast<std::size_t>(most));
}

Trainer::Impl::~Impl() { stop_threads(); }

void Trainer::Impl::start_threads() {
  rounds = std::make_unique<Rounds>();
  rounds->batches.reserve(static_cast<std::size_t>(config.trainer.simulation_threads));
  if (threads.empty())
    for (int i = 0; i < config.trainer.simulation_threads; ++i)
      threads.push_back(std::make_unique<SimulationThread>(config, callbacks.label_source));
  for (auto& s : threads) {
    // What an interrupted run may have left.
    s->episode = -1;
    s->ended = false;
    s->round_steps = s->stored = s->round_cost = 0;
    s->decisions.clear();
    s->decision_logs.clear();
    s->episode_decisions.clear();
    s->episode_decision_returns.clear();
    s->generation = 0;
    s->thread = std::thread([this, p = s.get()] { simulate(*p); });
  }
}

void Trainer::Impl::stop_threads() {
  if (!rounds) return;
  {
    std::lock_guard<std::mutex> lock(rounds->mutex);
    rounds->quit = true;
  }
  rounds->cv.notify_all();
  for (auto& s : threads) {
    if (s->thread.joinable()) s->thread.join();
    for (int p = 0; p < kPhases; ++p) threads_spent[p] += s->laps.spent[p];
    s->laps.spent = {};
  }
  // The learner thread's job reads the threads' buffers and the round's
  // lists. After a normal end it is done already; on an error's way out its
  // own error would only hide the first one.
  try {
    worker->wait();
  } catch (...) {
  }
  rounds.reset();
}

void Trainer::Impl::simulate(SimulationThread& s) {
  s.laps.start();
  try {
    while (true) {
      int episode = await_release(*rounds, s, false);
      while (episode >= 0) {
        play_in_thread(s, episode);
        episode = await_release(*rounds, s, true);
      }
    }
  } catch (const ThreadsStopped&) {
  } catch (...) {
    std::lock_guard<std::mutex> lock(rounds->mutex);
    if (!rounds->error) rounds->error = std::current_exception();
    rounds->cv.notify_all();
  }
  s.laps.lap(kWaiting);
  s.laps.on = false;
}

// As train_episode() with the thread's own parts: its transitions and
// decisions wait in its buffers for the round's end.
void Trainer::Impl::play_in_thread(SimulationThread& s, int episode) {
  const TrainerParams& t = config.trainer;
  const EpisodePlan plan = plan_episode(t, episode);
  s.rng.seed(stream_seed(t.seed, episode, 0));
  s.agent.motion->reseed(stream_seed(t.seed, episode, 1));
  if (s.agent.config_copy) s.agent.config_copy->reseed(stream_seed(t.seed, episode, 2));
  LearnHooks hooks;
  hooks.laps = &s.laps;
  hooks.motion = [&s, learning = !plan.refit](const rl::Observation& o, const rl::Action& a, float r,
                                              const rl::Observation& n, bool term, bool trunc, int steps) {
    if (!learning) return;
    s.agent.motion->count(term, trunc);
    s.pending[s.filling][static_cast<std::size_t>(s.stored++)].set(o, a, r, n, term, trunc, steps);
  };
  hooks.stepped = [this, &s](bool done) {
    ++s.round_steps;
    s.round_cost += step_cost(s.runner.env().modules());
    if (s.round_cost >= round_quota(config.trainer) && !done) await_release(*rounds, s, true);
  };
  hooks.motion_greedy = plan.greedy_motion;
  hooks.config = [this, &s, episode, learns = plan.config_learns](const rl::Observation& o, const rl::Action& a,
                                                                  float r2, const rl::Observation& n, bool term,
                                                                  bool trunc, int k) {
    if (!learns) return;
    if (config.trainer.config_target == ConfigTarget::episode_return) {
      Transition& d = s.episode_decisions.emplace_back();  // 2 or 3 an episode
      d.obs = o;
      d.next = n;
      d.action = a;
      s.episode_decision_returns.push_back(r2);
      if (term || trunc) {
        to_return_transitions(s.episode_decisions, s.episode_decision_returns, config.dqn.gamma);
        for (Transition& d : s.episode_decisions) s.decisions.push_back({std::move(d), 1});
        s.episode_decisions.clear();
      }
    } else {
      StoredDecision& sd = s.decisions.emplace_back();
      sd.transition.obs = o;
      sd.transition.next = n;
      sd.transition.action = a;
      sd.transition.reward = r2;
      sd.transition.terminated = term;
      sd.transition.truncated = trunc;
      sd.k = k;
    }
    if (callbacks.on_decision)
      s.decision_logs.push_back(decision_log(episode, s.runner.env().step_count(), a, r2, n, term, trunc, k));
  };
  if (plan.random_config)
    hooks.random_config = [&s](const std::vector<std::uint8_t>& mask) { return random_valid_action(mask, s.rng); };
  if (plan.pilot) {
    hooks.pilot = &s.pilot;
    hooks.pilot_drives = plan.scripted;
    hooks.pilot_noise = t.warmup_noise;
    hooks.pilot_rng = &s.rng;
  }
  s.log = s.runner.play(s.agent, plan.spec, true, &hooks);
  s.log.episode = episode;
  s.log.warmup = plan.warmup;
  s.ended = true;
}

void Trainer::Impl::sync_threads(bool all) {
  const bool refit = state.episode >= config.trainer.refit_start();
  for (auto& sp : threads) {
    SimulationThread& s = *sp;
    if (!all && s.episode < 0) continue;
    s.agent.motion->sync_from(*state.motion);
    const rl::Learner* dqn = state.agent.config.get();
    if (!dqn) continue;
    if (s.config_source != dqn) {  // the first time, and at the refit's start
      s.agent.config_copy = make_config_policy(config, refit);
      s.config_source = dqn;
      s.config_synced_updates = -1;
    }
    if (s.config_synced_updates != dqn->counters().updates) {
      s.agent.config_copy->sync_from(*dqn);
      s.config_synced_updates = dqn->counters().updates;
    }
    s.agent.config_copy->set_counters(dqn->counters());  // its epsilon's clock
  }
}

void Trainer::Impl::release_threads() {
  {
    std::lock_guard<std::mutex> lock(rounds->mutex);
    for (auto& s : threads) {
      if (s->episode < 0) continue;
      // The acting schedules' clocks: the run's counts (as one thread's would be).
      s->agent.motion->set_counters({state.steps, s->episode, 0});
    }
    ++rounds->generation;
  }
  rounds->cv.notify_all();
  laps.lap(kHandover);
}

void Trainer::Impl::wait_for_threads(int active) {
  std::unique_lock<std::mutex> lock(rounds->mutex);
  rounds->cv.wait(lock, [&] { return rounds->arrived == active || rounds->error; });
  if (rounds->error) std::rethrow_exception(rounds->error);
  rounds->arrived = 0;
  lock.unlock();
  laps.lap(kWaiting);
}

void Trainer::Impl::end_round() {
  // The learners' previous job done: their weights into the acting copies,
  // then the round's transitions (motion) and decisions (DQN), in thread
  // order, as the next job; it runs while the threads simulate the next round.
  worker->wait();
  laps.lap(kWaiting);
  sync_threads(false);
  std::vector<Rounds::Batch>& batches = rounds->batches;
  std::vector<StoredDecision>& decisions = rounds->decisions;
  batches.clear();
  decisions.clear();
  for (auto& s : threads) {
    if (s->stored > 0) batches.push_back({&s->pending[s->filling], s->stored});
    s->filling = 1 - s->filling;
    state.steps += s->round_steps;
    s->round_steps = s->stored = s->round_cost = 0;
    for (StoredDecision& d : s->decisions) decisions.push_back(std::move(d));
    s->decisions.clear();
    if (callbacks.on_decision)
      for (const DecisionLog& d : s->decision_logs) callbacks.on_decision(d);
    s->decision_logs.clear();
  }
  if (!batches.empty() || !decisions.empty()) {
    rl::Learner* motion = state.motion.get();
    rl::Learner* dqn = state.agent.config.get();
    Clock::duration* busy = &learner_busy;
    worker->submit([motion, dqn, &batches, &decisions, busy] {
      const Clock::time_point start = Clock::now();
      for (const Rounds::Batch& b : batches)
        for (int i = 0; i < b.count; ++i) {
          const Transition& t = (*b.transitions)[static_cast<std::size_t>(i)];
          store_and_update(*motion, t, t.steps);
        }
      for (const StoredDecision& d : decisions) store_and_update(*dqn, d.transition, d.k);
      *busy += Clock::now() - start;
    });
  }
  laps.lap(kHandover);
}

bool Trainer::Impl::run_simulation_threads(const std::atomic<bool>* stop) {
  const TrainerParams& t = config.trainer;
  const int total = t.total_episodes();
  start_threads();
  struct Joiner {
    Impl& m;
    ~Joiner() { m.stop_threads(); }
  } joiner{*this};
  std::map<int, EpisodeLog> ended;  // episodes that ended before an earlier one: rows go in index order
  while (state.episode < total) {
    // A stop is taken at a block's start only: a checkpoint inside a block
    // could not be resumed to the numbers of an uninterrupted run.
    if (stop && stop->load()) {
      checkpoint_in_run();
      return false;
    }
    if (state.episode == t.refit_start()) {  // as train_episode()
      state.agent.config = make_refit_config_model(config);
      state.config_segments = {};
    }
    // A block: episodes [state.episode, end) on the threads, each taking the
    // next index when its episode ends.
    const int end = block_end(t, state.episode);
    int next = state.episode, active = 0;
    sync_threads(true);
    {
      std::lock_guard<std::mutex> lock(rounds->mutex);
      for (auto& s : threads) {
        s->episode = next < end ? next++ : -1;
        active += s->episode >= 0;
      }
    }
    laps.lap(kOther);
    bool stop_said = false;
    while (active > 0) {
      if (stop && stop->load() && !stop_said) {
        std::fprintf(stderr, "stopping: the threads finish episodes %d to %d (a block), then the checkpoint\n",
                     state.episode + 1, end);
        stop_said = true;
      }
      release_threads();
      wait_for_threads(active);
      end_round();
      {
        std::lock_guard<std::mutex> lock(rounds->mutex);
        for (auto& s : threads) {
          if (!s->ended) continue;
          s->ended = false;
          ended.emplace(s->log.episode, std::move(s->log));
          s->episode = next < end ? next++ : -1;
          active -= s->episode < 0;
        }
      }
      laps.lap(kOther);
      for (auto e = ended.begin(); e != ended.end() && e->first == state.episode; e = ended.erase(e)) {
        ++state.episode;
        log_episode(e->second);
      }
    }
    // The block's end: the learner catches up; then as run()'s loop after an episode.
    worker->wait();
    laps.lap(kWaiting);
    state.agent.motion->sync_from(*state.motion);
    state.agent.motion->set_counters({state.steps, state.episode, 0});
    laps.lap(kHandover);
    const bool last = state.episode == total;
    if (t.eval_interval > 0 && (state.episode % t.eval_interval == 0 || last)) evaluate_in_run();
    if (state.episode % t.checkpoint_interval == 0 || last) checkpoint_in_run();
  }
  return true;
}

}  // namespace comorph::coopt
