// The hierarchical trainer (see trainer.hpp for the loop): one training
// episode's hooks, the hand-over to the learner thread, periodic evaluation,
// progress lines, and run(). Its parts: trainer_impl.hpp.
#include "coopt/trainer.hpp"

#include <torch/torch.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "coopt/segment.hpp"
#include "coopt/trainer_impl.hpp"
#include "rl/learner.hpp"
#include "rl/policy.hpp"

namespace comorph::coopt {

Trainer::Impl::Impl(const CooptConfig& c, const std::string& dir, TrainerCallbacks cb)
    : config(c), store(dir), callbacks(std::move(cb)), runner(config, callbacks.label_source),
      state(config) {
  for (auto& p : pending) allocate_transitions(c, p, static_cast<std::size_t>(c.trainer.sync_interval));
  worker = std::make_unique<LearnerWorker>(c.trainer.learner_thread);
  configure_pilot(c.trainer, pilot);
}

void allocate_transitions(const CooptConfig& c, std::vector<Transition>& v, std::size_t n) {
  v.resize(n);
  for (Transition& t : v) {
    rl::allocate(motion_spec(c), t.obs);
    rl::allocate(motion_spec(c), t.next);
    t.action.continuous.assign(control::kActionSize, 0.0f);
    t.action.target.assign(control::kActionSize, 0.0f);  // so that copying a target does not allocate
  }
}

EpisodePlan plan_episode(const TrainerParams& t, int episode) {
  EpisodePlan p;
  p.warmup = episode < t.warmup_episodes;
  p.refit = episode >= t.refit_start();
  p.scripted = !p.refit && t.warmup_policy == WarmupPolicy::scripted &&
               (p.warmup || (t.scripted_interval > 0 && episode % t.scripted_interval == 0));
  p.greedy_motion = p.refit || (!p.warmup && !p.scripted && t.greedy_motion_interval > 0 &&
                                episode % t.greedy_motion_interval == 1 % t.greedy_motion_interval);
  p.config_learns = p.refit || t.config_learns_from == ConfigLearnsFrom::all ||
                    (t.config_learns_from == ConfigLearnsFrom::model && !p.scripted) ||
                    (t.config_learns_from == ConfigLearnsFrom::greedy && p.greedy_motion);
  p.random_config = p.warmup || (p.scripted && t.pilot_random_configs);
  p.pilot = p.scripted || (t.pilot_labels && !p.refit);
  p.spec.seed = static_cast<std::uint64_t>(t.seed) * 1000003ULL + static_cast<std::uint64_t>(episode);
  p.spec.stair_height = t.stair_height;
  const task::ScenarioSpec& scenario = task::scenario_spec(t.scenario);
  p.spec.obstacles = scenario.obstacles;
  p.spec.variant = scenario.variant;
  return p;
}

int random_valid_action(const std::vector<std::uint8_t>& mask, std::mt19937_64& rng) {
  int valid = 0;
  for (auto m : mask) valid += m;
  int k = std::uniform_int_distribution<int>(0, valid - 1)(rng);
  for (int a = 0; a < static_cast<int>(mask.size()); ++a)
    if (mask[a] && k-- == 0) return a;
  return -1;
}

DecisionLog decision_log(int episode, int step, const rl::Action& a, float r2, const rl::Observation& next,
                         bool terminated, bool truncated, int k) {
  DecisionLog d;
  d.episode = episode;
  d.step = step;
  d.modules = modules_of(a.discrete);
  d.r2 = r2;
  d.k = k;
  for (int c = 0; c < kCandidates; ++c)
    if (next.valid_actions[c]) d.next_max_modules = modules_of(c);
  d.terminated = terminated;
  d.truncated = truncated;
  return d;
}

double Trainer::Impl::wall() const {
  return state.wall_before + std::chrono::duration<double>(Clock::now() - started).count();
}

// Hands the filled transitions to the learner (after its previous job) and
// refreshes the policy's weights from the learner.
void Trainer::Impl::hand_over() {
  laps.lap(kHandover);
  worker->wait();
  laps.lap(kWaiting);
  state.agent.motion->sync_from(*state.motion);
  laps.lap(kHandover);
  if (filled == 0) return;
  std::vector<Transition>* batch = &pending[filling];
  const int n = filled;
  filling = 1 - filling;
  filled = 0;
  rl::Learner* l = state.motion.get();
  Clock::duration* busy = &learner_busy;
  worker->submit([l, batch, n, busy] {
    const Clock::time_point start = Clock::now();
    for (int i = 0; i < n; ++i) {
      const Transition& t = (*batch)[i];
      l->store(t.obs, t.action, t.reward, t.next, t.terminated, t.truncated, t.steps);
      for (int u = l->updates_due(); u > 0; --u) l->update();
    }
    *busy += Clock::now() - start;
  });
  laps.lap(config.trainer.learner_thread ? kHandover : kMotionUpdates);  // inline: the job ran in submit()
}

// Episode end: everything handed over and learnt, the policy up to date.
void Trainer::Impl::full_sync() {
  hand_over();
  worker->wait();
  laps.lap(kWaiting);
  state.agent.motion->sync_from(*state.motion);
  laps.lap(kHandover);
}

// trainer.config_target: return. Each decision of the ended episode is
// stored with the R2 of its own and every later segment (each later one
// discounted once more by dqn.gamma) as a terminal transition.
void Trainer::Impl::learn_episode_returns() {
  to_return_transitions(episode_decisions, episode_decision_returns, config.dqn.gamma);
  for (const Transition& d : episode_decisions) store_and_update(*state.agent.config, d);
  episode_decisions.clear();
}

void to_return_transitions(std::vector<Transition>& decisions, std::vector<float>& r2, double gamma) {
  to_decision_returns(r2, gamma);
  for (std::size_t i = 0; i < decisions.size(); ++i) {
    // Terminal: no bootstrap, so the segment's length (the discount's k) plays no part.
    decisions[i].reward = r2[i];
    decisions[i].terminated = true;
    decisions[i].truncated = false;
  }
  r2.clear();
}

void store_and_update(rl::Learner& l, const Transition& t, int k) {
  l.store(t.obs, t.action, t.reward, t.next, t.terminated, t.truncated, k);
  for (int u = l.updates_due(); u > 0; --u) l.update();
}

EpisodeLog Trainer::Impl::train_episode() {
  const TrainerParams& t = config.trainer;
  const EpisodePlan plan = plan_episode(t, state.episode);
  // The DQN refit (trainer.config_refit_episodes): a fresh DQN on the frozen,
  // greedy motion model; no pilot, nothing stored for the motion learner.
  if (plan.refit && state.episode == t.refit_start()) {
    state.agent.config = make_refit_config_model(config);
    state.config_segments = {};  // its replay starts empty: no segment of the old one to link
  }
  LearnHooks hooks;
  hooks.laps = &laps;
  if (plan.refit)
    hooks.motion = [this](const rl::Observation&, const rl::Action&, float, const rl::Observation&, bool, bool,
                          int) { ++state.steps; };
  else
    hooks.motion = [this](const rl::Observation& o, const rl::Action& a, float r, const rl::Observation& n,
                          bool term, bool trunc, int steps) {
      state.agent.motion->count(term, trunc);  // the acting side's exploration schedule
      Transition& tr = record ? (*record)[recorded++] : pending[filling][filled++];
      tr.set(o, a, r, n, term, trunc, steps);
      ++state.steps;
      if (!record && filled == config.trainer.sync_interval) hand_over();
    };
  hooks.motion_greedy = plan.greedy_motion;
  hooks.config = [this, learns = plan.config_learns](const rl::Observation& o, const rl::Action& a, float r2,
                                                     const rl::Observation& n, bool term, bool trunc, int k) {
    if (!learns) return;
    if (config.trainer.config_target == ConfigTarget::episode_return) {
      Transition& d = episode_decisions.emplace_back();  // 2 or 3 an episode
      d.obs = o;
      d.next = n;
      d.action = a;
      episode_decision_returns.push_back(r2);
      if (term || trunc) learn_episode_returns();
    } else {
      state.agent.config->store(o, a, r2, n, term, trunc, k);
      for (int u = state.agent.config->updates_due(); u > 0; --u) state.agent.config->update();
    }
    if (callbacks.on_decision)
      callbacks.on_decision(decision_log(state.episode, runner.env().step_count(), a, r2, n, term, trunc, k));
  };
  if (plan.random_config)
    hooks.random_config = [this](const std::vector<std::uint8_t>& mask) { return random_valid_action(mask, state.rng); };
  if (plan.pilot) {
    hooks.pilot = &pilot;
    hooks.pilot_drives = plan.scripted;
    hooks.pilot_noise = t.warmup_noise;
    hooks.pilot_rng = &state.rng;
  }
  EpisodeLog log = runner.play(state.agent, plan.spec, true, &hooks);
  if (!record) full_sync();
  log.episode = state.episode;
  log.warmup = plan.warmup;
  return log;
}

EvaluationLog Trainer::Impl::periodic_evaluation() {
  EvaluationLog e;
  e.train_episode = state.episode;
  e.env_steps = state.steps;
  e.wall_s = wall();
  for (int i = 0; i < config.trainer.eval_episodes; ++i) {
    const auto spec = eval_spec(config, task::scenario_spec(config.trainer.scenario),
                                static_cast<std::uint64_t>(config.trainer.eval_seed) + i, i);
    EpisodeLog log = runner.play(state.agent, spec, false);
    log.episode = i;
    e.episodes.push_back(std::move(log));
  }
  return e;
}

void Trainer::Impl::progress(const EpisodeLog& log) {
  recent_success.push_back(log.success ? 1.0 : 0.0);
  if (recent_success.size() > 20) recent_success.erase(recent_success.begin());
  const TrainerParams& t = config.trainer;
  const int total = t.total_episodes();
  recent_wall.push_back(wall());
  if (recent_wall.size() > 101) recent_wall.pop_front();
  if (state.episode % t.progress_interval != 0 && state.episode != total) return;
  double rate = 0;
  for (double s : recent_success) rate += s;
  rate /= static_cast<double>(recent_success.size());
  const double w = recent_wall.back();
  // Wall per episode over the recent ones once there are 10, the run's average before.
  const double episode_s = recent_wall.size() > 10 ? (w - recent_wall.front()) / static_cast<double>(recent_wall.size() - 1)
                           : state.episode > 0    ? w / state.episode
                                                  : 0;
  const double eta_s = episode_s * (total - state.episode);
  const std::string configs = task::configuration_sequence(log.configurations);
  std::fprintf(stderr,
               "episode %d/%d%s%s | %d steps, return %.1f, %s | total %lld steps, %.0f steps/s | success %.0f %% "
               "(last %zu) | config %s (stairs %.2f m) | wall %.0f s, ETA %.0f s\n",
               state.episode, total, log.warmup ? " (warm-up)" : "",
               state.episode > t.refit_start() ? " (DQN refit)" : "", log.steps, log.return_R1, log.termination.c_str(),
               static_cast<long long>(state.steps), w > 0 ? state.steps / w : 0.0, 100.0 * rate, recent_success.size(),
               configs.c_str(), log.stair_height_m, w, eta_s);
}

Trainer::Trainer(const CooptConfig& config, const std::string& run_dir, TrainerCallbacks callbacks)
    : impl_(std::make_unique<Impl>(config, run_dir, std::move(callbacks))) {}
Trainer::~Trainer() = default;

void Trainer::resume() { impl_->load_checkpoint(); }
int Trainer::episodes_done() const { return impl_->state.episode; }
std::int64_t Trainer::env_steps() const { return impl_->state.steps; }
double Trainer::wall_s() const { return impl_->wall(); }

TrainerTiming Trainer::timing() const {
  const Impl& m = *impl_;
  auto s = [](Clock::duration d) { return std::chrono::duration<double>(d).count(); };
  TrainerTiming t;
  t.wall_s = s(m.run_time);
  using Field = double TrainerTiming::*;
  const std::pair<Phase, Field> fields[] = {
      {kEnvStep, &TrainerTiming::env_step_s},       {kEnvReset, &TrainerTiming::env_reset_s},
      {kActing, &TrainerTiming::acting_s},          {kHandover, &TrainerTiming::handover_s},
      {kWaiting, &TrainerTiming::waiting_s},        {kMotionUpdates, &TrainerTiming::motion_updates_s},
      {kDqn, &TrainerTiming::dqn_s},                {kClassifier, &TrainerTiming::classifier_s},
      {kEvaluation, &TrainerTiming::evaluation_s},  {kCheckpoint, &TrainerTiming::checkpoint_s},
      {kLogging, &TrainerTiming::logging_s},        {kOther, &TrainerTiming::other_s}};
  std::array<Clock::duration, kPhases> spent = m.laps.spent;
  if (m.config.trainer.simulation_threads > 1) {
    // The simulation threads' mean. The trainer's thread closes the rounds,
    // evaluates, checkpoints and logs while they wait: that moves from their
    // waiting to its phases (the DQN learns on the learner thread).
    const auto n = static_cast<Clock::rep>(m.config.trainer.simulation_threads);
    for (int p = 0; p < kPhases; ++p) spent[p] = m.threads_spent[p] / n;
    for (Phase p : {kHandover, kEvaluation, kCheckpoint, kLogging}) {
      spent[kWaiting] -= m.laps.spent[p];
      spent[p] += m.laps.spent[p];
    }
  }
  for (const auto& [phase, field] : fields) t.*field = s(spent[phase]);
  t.learner_busy_s = s(m.learner_busy);
  t.checkpoints = m.run_checkpoints;
  return t;
}

bool Trainer::run(const std::atomic<bool>* stop) {
  Impl& m = *impl_;
  const TrainerParams& t = m.config.trainer;
  const int total = t.total_episodes();
  // run()'s time is timed, and every return (or exception) ends the laps.
  struct RunClock {
    Impl& m;
    Clock::time_point start = Clock::now();
    explicit RunClock(Impl& impl) : m(impl) { m.laps.start(); }
    ~RunClock() {
      m.laps.lap(kOther);
      m.laps.on = false;
      m.run_time += Clock::now() - start;
    }
  } run_clock(m);
  if (!m.run_files) {
    if (!t.refit_motion_from.empty()) m.take_motion_model(t.refit_motion_from);
    m.store.create(m.config);
    m.run_files = true;
  }
  if (t.simulation_threads > 1) return m.run_simulation_threads(stop);
  while (m.state.episode < total) {
    if (stop && stop->load()) {
      m.checkpoint_in_run();
      return false;
    }
    const EpisodeLog log = m.train_episode();
    ++m.state.episode;
    m.laps.lap(kOther);
    m.log_episode(log);
    const bool last = m.state.episode == total;
    if (t.eval_interval > 0 && (m.state.episode % t.eval_interval == 0 || last)) m.evaluate_in_run();
    if (m.state.episode % t.checkpoint_interval == 0 || last) m.checkpoint_in_run();
  }
  return true;
}

void Trainer::Impl::take_motion_model(const std::string& run_dir) {
  const CheckpointInfo source = read_checkpoint_info(run_dir);
  const std::string path = (std::filesystem::path(source.directory) / "motion_actor.pt").string();
  try {
    // The networks only: this run's learner counts its own (no) transitions.
    state.motion->load_acting_networks(path);
  } catch (const c10::Error& e) {
    throw std::runtime_error("trainer.refit_motion_from: " + path + ": its motion model does not fit this run's (" +
                             config.trainer.motion_algo + ", the motion inputs and network sizes must be the same): " +
                             e.what_without_backtrace());
  } catch (const std::exception& e) {
    throw std::runtime_error("trainer.refit_motion_from: " + path + ": its motion model does not fit this run's (" +
                             config.trainer.motion_algo + ", the motion inputs and network sizes must be the same): " +
                             e.what());
  }
  state.agent.motion->sync_from(*state.motion);
  std::fprintf(stderr, "refit of the motion model of %s (%d episodes, %s)\n", run_dir.c_str(), source.episodes,
               source.directory.c_str());
}

void Trainer::Impl::log_episode(const EpisodeLog& log) {
  store.append_episode(log);
  if (callbacks.on_episode) callbacks.on_episode(log);
  progress(log);
  laps.lap(kLogging);
}

void Trainer::Impl::evaluate_in_run() {
  const EvaluationLog e = periodic_evaluation();
  ++state.evaluations;
  laps.lap(kEvaluation);
  std::fprintf(stderr, "%s\n", store.append_evaluation(config, e).c_str());
  if (callbacks.on_evaluation) callbacks.on_evaluation(e);
  laps.lap(kLogging);
}

void Trainer::Impl::checkpoint_in_run() {
  save_checkpoint();
  laps.lap(kCheckpoint);
  ++run_checkpoints;
}

}  // namespace comorph::coopt
