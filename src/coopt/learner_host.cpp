#include "coopt/learner_host.hpp"

#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "coopt/run_store.hpp"
#include "coopt/segment.hpp"
#include "rl/learner.hpp"
#include "rl/policy.hpp"

namespace comorph::coopt {
namespace {

void copy_transition(const Transition& from, Transition& to) {
  to.set(from.obs, from.action, from.reward, from.next, from.terminated, from.truncated, from.steps);
}

bool training_episode(const TrainerParams& t, int episode) {
  return episode >= t.warmup_episodes && episode < t.refit_start();
}

// The training episodes a curriculum draws for and learns from: after the warm-up, before the refit.
bool curriculum_episode(const TrainerParams& t, int episode) {
  return t.stair_curriculum > 0 && training_episode(t, episode);
}
bool chain_curriculum_episode(const TrainerParams& t, int episode) {
  return t.chain_curriculum > 0 && training_episode(t, episode);
}

}  // namespace

LearnerHost::LearnerHost(const CooptConfig& c, const std::string& run_dir, TrainerCallbacks callbacks, int actors)
    : config_(c), store_(run_dir), callbacks_(std::move(callbacks)), one_actor_(actors == 1), state_(config_),
      runner_(config_, callbacks_.label_source), worker_(std::make_unique<LearnerWorker>(c.trainer.learner_thread)),
      orders_(static_cast<std::size_t>(actors)) {
  const TrainerParams& t = c.trainer;
  // One actor hands over an interval at a time; lockstep, a round of every actor.
  const int round = (round_quota(t) + step_cost(kMinModules) - 1) / step_cost(kMinModules) + t.motion_n_step - 1;
  const int most = one_actor_ ? t.sync_interval : actors * round;
  for (auto& p : pending_) allocate_transitions(c, p, static_cast<std::size_t>(most));
}

LearnerHost::~LearnerHost() {
  // The learner thread's job reads pending_. After a normal end it is done
  // already; on an error's way out its own error would only hide the first one.
  try {
    worker_->wait();
  } catch (...) {
  }
}

double LearnerHost::wall() const {
  return state_.wall_before + std::chrono::duration<double>(Clock::now() - started_).count();
}

void LearnerHost::start_run() {
  if (run_files_) return;
  if (!config_.trainer.refit_motion_from.empty()) take_motion_model(config_.trainer.refit_motion_from);
  store_.create(config_);
  run_files_ = true;
}

void LearnerHost::resume() {
  store_.load_checkpoint(state_, config_);
  started_ = Clock::now();
  run_files_ = true;
}

// The weights change only in updates: unchanged ones keep their version, and
// an actor that holds it copies nothing (the refit's frozen motion model).
void LearnerHost::refresh_motion() {
  const std::int64_t updates = state_.motion->counters().updates;
  if (weights_.motion_version > 0 && updates == motion_updates_) return;
  rl::acting_weights(*state_.motion, weights_.motion);
  ++weights_.motion_version;
  motion_updates_ = updates;
}

void LearnerHost::refresh_config() {
  if (!state_.config) return;
  const std::int64_t updates = state_.config->counters().updates;
  if (weights_.config_version == 0 || updates != config_updates_ || weights_.config_refit != state_.config_refit) {
    rl::acting_weights(*state_.config, weights_.config);
    ++weights_.config_version;
    config_updates_ = updates;
    weights_.config_refit = state_.config_refit;
  }
  weights_.config_counters = state_.config->counters();
}

Orders LearnerHost::start_orders(int episode) const {
  Orders o;
  o.episode = episode;
  o.start = true;
  o.set_motion_counters = true;
  o.set_config_rng = state_.config != nullptr;
  if (one_actor_) {  // the run's streams go on
    o.rng = state_.rng;
    o.motion_rng = state_.agent.motion->rng();
    o.motion_counters = state_.agent.motion->counters();
    if (state_.config) o.config_rng = state_.config->rng();
  } else {  // the episode's own streams; the run's counts as the schedules' clock
    const int seed = config_.trainer.seed;
    o.rng.seed(stream_seed(seed, episode, 0));
    o.motion_rng.seed(stream_seed(seed, episode, 1));
    o.config_rng.seed(stream_seed(seed, episode, 2));
    o.motion_counters = {state_.steps, episode, 0};
  }
  const TrainerParams& t = config_.trainer;
  if (curriculum_episode(t, episode))
    o.stair_height_m = state_.curriculum.draw(height_weights_, stream_seed(t.seed, episode, 3));
  if (chain_curriculum_episode(t, episode)) {
    if (uniform_from(stream_seed(t.seed, episode, 4)) < t.chain_curriculum) {
      const ChainCurriculum::Pair pair = state_.chain_curriculum.draw(pair_weights_, stream_seed(t.seed, episode, 5));
      o.stair_height_m = pair.height_m;
      o.first_config = candidate_of(pair.modules);
    }
  }
  return o;
}

void LearnerHost::begin_block() {
  const TrainerParams& t = config_.trainer;
  if (state_.episode == t.refit_start()) {
    // The DQN refit (trainer.config_refit_episodes): a fresh DQN on the frozen,
    // greedy motion model; its replay starts empty, no segment of the old one to link.
    state_.start_refit(config_);
    state_.config_segments = {};
    if (t.keep_best_motion) take_best_motion();
    if (t.motion_average_episodes > 0) take_average_motion();
  }
  end_ = one_actor_ ? state_.episode + 1 : block_end(t, state_.episode);
  next_ = state_.episode;
  // Fixed for the block: every actor count draws from the same probabilities.
  if (t.stair_curriculum > 0) height_weights_ = state_.curriculum.weights(t.stair_curriculum);
  if (t.chain_curriculum > 0) pair_weights_ = state_.chain_curriculum.weights();
  refresh_motion();
  refresh_config();
  active_ = 0;
  for (Orders& o : orders_) {
    o = next_ < end_ ? start_orders(next_++) : Orders{};
    active_ += o.episode >= 0;
  }
  laps.lap(kHandover);
}

// The learner thread's next job: `transitions` of pending_[filling_] for the
// motion learner, then `decisions` (may be null) for the configuration model.
void LearnerHost::submit(int transitions, const std::vector<StoredDecision>* decisions) {
  std::vector<Transition>* batch = &pending_[filling_];
  filling_ = 1 - filling_;
  filled_ = 0;
  rl::Learner* motion = state_.motion.get();
  rl::Learner* dqn = state_.config.get();
  Clock::duration* busy = &learner_busy_;
  worker_->submit([motion, dqn, batch, transitions, decisions, busy] {
    const Clock::time_point start = Clock::now();
    for (int i = 0; i < transitions; ++i) {
      const Transition& t = (*batch)[static_cast<std::size_t>(i)];
      store_and_update(*motion, t, t.steps);
    }
    if (decisions)
      for (const StoredDecision& d : *decisions) store_and_update(*dqn, d.transition, d.k);
    *busy += Clock::now() - start;
  });
  laps.lap(config_.trainer.learner_thread ? kHandover : kMotionUpdates);  // inline: the job ran in submit()
}

void LearnerHost::hand_over() {
  laps.lap(kHandover);
  worker_->wait();
  laps.lap(kWaiting);
  refresh_motion();
  laps.lap(kHandover);
  if (filled_ > 0) submit(filled_, nullptr);
}

void LearnerHost::full_sync() {
  hand_over();
  worker_->wait();
  laps.lap(kWaiting);
  refresh_motion();
  laps.lap(kHandover);
}

void LearnerHost::ingest(std::vector<Rollout*>& rollouts) {
  laps.lap(kWaiting);
  if (one_actor_)
    ingest_one(*rollouts[0]);
  else
    ingest_lockstep(rollouts);
}

void LearnerHost::ingest_one(Rollout& r) {
  Orders& o = orders_[0];
  o.start = o.set_motion_counters = false;
  if (state_.config) state_.config->set_rng(r.config_rng);  // the one DQN stream, drawn by the actor since
  for (int i = 0; i < r.stored; ++i) {
    const Transition& t = r.transitions[static_cast<std::size_t>(i)];
    if (record_) {
      copy_transition(t, (*record_)[recorded_++]);
      continue;
    }
    copy_transition(t, pending_[filling_][static_cast<std::size_t>(filled_++)]);
    if (filled_ == config_.trainer.sync_interval) hand_over();
  }
  state_.steps += r.steps;
  laps.lap(kHandover);
  for (const StoredDecision& d : r.decisions) store_and_update(*state_.config, d.transition, d.k);
  laps.lap(kDqn);
  if (callbacks_.on_decision)
    for (const DecisionLog& d : r.decision_logs) callbacks_.on_decision(d);
  laps.lap(kLogging);
  if (r.ended) {
    if (!record_) full_sync();
    state_.rng = r.rng;
    state_.agent.motion->set_rng(r.motion_rng);
    state_.agent.motion->set_counters(r.motion_counters);
    o = Orders{};
    active_ = 0;
    ++state_.episode;
    laps.lap(kOther);
    if (!record_) log_episode(r.log);  // measure_side_rates writes nothing
  }
  refresh_config();
  if (state_.config) {
    o.set_config_rng = true;
    o.config_rng = state_.config->rng();
  }
  laps.lap(kHandover);
}

void LearnerHost::ingest_lockstep(std::vector<Rollout*>& rollouts) {
  // The learners' previous job done: their weights out, then the round's
  // transitions (motion) and decisions (DQN), actor by actor, as the next
  // job; it runs while the actors simulate the next round.
  worker_->wait();
  laps.lap(kWaiting);
  refresh_motion();
  refresh_config();
  job_decisions_.clear();
  int n = 0;
  for (Rollout* r : rollouts) {
    if (!r) continue;
    for (int i = 0; i < r->stored; ++i)
      copy_transition(r->transitions[static_cast<std::size_t>(i)], pending_[filling_][static_cast<std::size_t>(n++)]);
    state_.steps += r->steps;
    for (StoredDecision& d : r->decisions) job_decisions_.push_back(std::move(d));
    if (callbacks_.on_decision)
      for (const DecisionLog& d : r->decision_logs) callbacks_.on_decision(d);
  }
  if (n > 0 || !job_decisions_.empty()) submit(n, &job_decisions_);
  laps.lap(kHandover);
  for (std::size_t i = 0; i < orders_.size(); ++i) {
    Orders& o = orders_[i];
    o.start = o.set_config_rng = false;
    if (rollouts[i] && rollouts[i]->ended) {
      ended_.emplace(rollouts[i]->log.episode, std::move(rollouts[i]->log));
      o = next_ < end_ ? start_orders(next_++) : Orders{};
      active_ -= o.episode < 0;
    }
    // The acting schedules' clocks: the run's counts (as one actor's would be).
    o.set_motion_counters = o.episode >= 0;
    o.motion_counters = {state_.steps, o.episode, 0};
  }
  laps.lap(kOther);
  for (auto e = ended_.begin(); e != ended_.end() && e->first == state_.episode; e = ended_.erase(e)) {
    ++state_.episode;
    log_episode(e->second);
  }
}

void LearnerHost::end_block() {
  const TrainerParams& t = config_.trainer;
  worker_->wait();
  laps.lap(kWaiting);
  state_.agent.motion->sync_from(*state_.motion);
  if (!one_actor_) state_.agent.motion->set_counters({state_.steps, state_.episode, 0});
  laps.lap(kHandover);
  if (record_) return;  // measure_side_rates: the acting side alone
  const bool last = state_.episode == t.total_episodes();
  const bool refit_start = t.keep_best_motion && state_.episode == t.refit_start();  // the last model's score too
  if (t.eval_interval > 0 && (state_.episode % t.eval_interval == 0 || last || refit_start)) {
    const EvaluationLog e = periodic_evaluation();
    ++state_.evaluations;
    laps.lap(kEvaluation);
    std::fprintf(stderr, "%s\n", store_.append_evaluation(config_, e).c_str());
    if (t.keep_best_motion && state_.episode <= t.refit_start()) keep_if_best(e);
    if (callbacks_.on_evaluation) callbacks_.on_evaluation(e);
    laps.lap(kLogging);
  }
  if (t.motion_average_snapshot(state_.episode)) add_motion_snapshot();
  if (state_.episode % t.checkpoint_interval == 0 || last) checkpoint();
}

void LearnerHost::checkpoint() {
  full_sync();
  state_.agent.motion->sync_from(*state_.motion);
  store_.save_checkpoint(state_, config_, wall());
  laps.lap(kCheckpoint);
  ++run_checkpoints_;
}

EvaluationLog LearnerHost::periodic_evaluation() {
  if (state_.config) state_.agent.config->sync_from(*state_.config);
  EvaluationLog e;
  e.train_episode = state_.episode;
  e.env_steps = state_.steps;
  e.wall_s = wall();
  for (int i = 0; i < config_.trainer.eval_episodes; ++i) {
    const auto spec = eval_spec(config_, task::scenario_spec(config_.trainer.scenario),
                                static_cast<std::uint64_t>(config_.trainer.eval_seed) + i, i);
    EpisodeLog log = runner_.play(state_.agent, spec, false);
    log.episode = i;
    e.episodes.push_back(std::move(log));
  }
  return e;
}

void LearnerHost::keep_if_best(const EvaluationLog& e) {
  const report::EvalSummary m = evaluation_summary(config_, e);
  const double success = m.success_rate.at("avg");
  const bool better = !state_.best_motion || success > state_.best_motion_success ||
                      (success == state_.best_motion_success && m.F > state_.best_motion_F);
  if (!better) return;
  if (!state_.best_motion) state_.best_motion = make_motion_policy(config_, 0);
  state_.best_motion->sync_from(*state_.motion);  // the evaluated networks: the learner has not updated since
  state_.best_motion_episode = e.train_episode;
  state_.best_motion_success = success;
  state_.best_motion_F = m.F;
}

void LearnerHost::take_motion(const rl::Policy& kept) {
  // Through a file: a learner takes acting networks only from one (Learner::load_acting_networks).
  const std::string path = store_.path("kept_motion_actor.pt.tmp");
  kept.save(path);
  state_.motion->load_acting_networks(path);
  std::filesystem::remove(path);
  state_.agent.motion->sync_from(*state_.motion);
  motion_updates_ = -1;  // new weights without an update: the actors must get them
}

void LearnerHost::take_best_motion() {
  if (!state_.best_motion) throw std::logic_error("trainer.keep_best_motion: no evaluated motion model at the refit");
  take_motion(*state_.best_motion);
  std::fprintf(stderr,
               "refit: the motion model of the evaluation after %d episodes (success %.2f, F(H) %.3f; "
               "trainer.keep_best_motion)\n",
               state_.best_motion_episode, state_.best_motion_success, state_.best_motion_F);
}

void LearnerHost::add_motion_snapshot() {
  if (!state_.motion_average) state_.motion_average = make_motion_policy(config_, 0);
  ++state_.motion_average_snapshots;
  state_.motion_average->blend_from(*state_.motion, 1.0 / state_.motion_average_snapshots);
}

void LearnerHost::take_average_motion() {
  if (!state_.motion_average) throw std::logic_error("trainer.motion_average_episodes: no snapshot at the refit");
  take_motion(*state_.motion_average);
  std::fprintf(stderr, "refit: the mean of %d snapshots of the motion model (trainer.motion_average_episodes %d)\n",
               state_.motion_average_snapshots, config_.trainer.motion_average_episodes);
}

void LearnerHost::take_motion_model(const std::string& run_dir) {
  const CheckpointInfo source = read_checkpoint_info(run_dir);
  const std::string path = (std::filesystem::path(source.directory) / "motion_actor.pt").string();
  const std::string what = "trainer.refit_motion_from: " + path + ": its motion model does not fit this run's (" +
                           config_.trainer.motion_algo + ", the motion inputs and network sizes must be the same): ";
  try {
    // The networks only: this run's learner counts its own (no) transitions.
    state_.motion->load_acting_networks(path);
  } catch (const c10::Error& e) {
    throw std::runtime_error(what + e.what_without_backtrace());
  } catch (const std::exception& e) {
    throw std::runtime_error(what + e.what());
  }
  state_.agent.motion->sync_from(*state_.motion);
  std::fprintf(stderr, "refit of the motion model of %s (%d episodes, %s)\n", run_dir.c_str(), source.episodes,
               source.directory.c_str());
}

void LearnerHost::log_episode(const EpisodeLog& log) {
  const TrainerParams& t = config_.trainer;
  if (curriculum_episode(t, log.episode)) state_.curriculum.record(log.stair_height_m, log.success);
  if (chain_curriculum_episode(t, log.episode) && !log.configurations.empty())
    state_.chain_curriculum.record(log.stair_height_m, log.configurations.front(), log.stairs_climbed);
  store_.append_episode(log);
  if (callbacks_.on_episode) callbacks_.on_episode(log);
  progress(log);
  laps.lap(kLogging);
}

void LearnerHost::progress(const EpisodeLog& log) {
  recent_success_.push_back(log.success ? 1.0 : 0.0);
  if (recent_success_.size() > 20) recent_success_.erase(recent_success_.begin());
  const TrainerParams& t = config_.trainer;
  const int total = t.total_episodes();
  const int episode = state_.episode;
  recent_wall_.push_back(wall());
  if (recent_wall_.size() > 101) recent_wall_.pop_front();
  if (episode % t.progress_interval != 0 && episode != total) return;
  double rate = 0;
  for (double s : recent_success_) rate += s;
  rate /= static_cast<double>(recent_success_.size());
  const double w = recent_wall_.back();
  // Wall per episode over the recent ones once there are 10, the run's average before.
  const double episode_s = recent_wall_.size() > 10 ? (w - recent_wall_.front()) / static_cast<double>(recent_wall_.size() - 1)
                           : episode > 0            ? w / episode
                                                    : 0;
  const double eta_s = episode_s * (total - episode);
  const std::string configs = task::configuration_sequence(log.configurations);
  std::string curriculum;  // the next training episodes' stair-height probabilities
  if (curriculum_episode(t, episode)) {
    curriculum = " | heights drawn";
    const std::vector<double> weights = state_.curriculum.weights(t.stair_curriculum);
    for (std::size_t i = 0; i < weights.size(); ++i) {
      char part[16];
      std::snprintf(part, sizeof part, "%s%.0f", i > 0 ? "/" : " ", 100.0 * weights[i]);
      curriculum += part;
    }
    curriculum += " %";
  }
  std::fprintf(stderr,
               "episode %d/%d%s%s | %d steps, return %.1f, %s | total %lld steps, %.0f steps/s | success %.0f %% "
               "(last %zu) | config %s (stairs %.2f m)%s | wall %.0f s, ETA %.0f s\n",
               episode, total, log.warmup ? " (warm-up)" : "", episode > t.refit_start() ? " (DQN refit)" : "",
               log.steps, log.return_R1, log.termination.c_str(), static_cast<long long>(state_.steps),
               w > 0 ? state_.steps / w : 0.0, 100.0 * rate, recent_success_.size(), configs.c_str(),
               log.stair_height_m, curriculum.c_str(), w, eta_s);
}

TrainerTiming LearnerHost::timing(const std::array<Clock::duration, kPhases>& actor_time, int actors) const {
  auto s = [](Clock::duration d) { return std::chrono::duration<double>(d).count(); };
  TrainerTiming t;
  t.wall_s = s(run_time);
  using Field = double TrainerTiming::*;
  const std::pair<Phase, Field> fields[] = {
      {kEnvStep, &TrainerTiming::env_step_s},       {kEnvReset, &TrainerTiming::env_reset_s},
      {kActing, &TrainerTiming::acting_s},          {kHandover, &TrainerTiming::handover_s},
      {kWaiting, &TrainerTiming::waiting_s},        {kMotionUpdates, &TrainerTiming::motion_updates_s},
      {kDqn, &TrainerTiming::dqn_s},                {kClassifier, &TrainerTiming::classifier_s},
      {kEvaluation, &TrainerTiming::evaluation_s},  {kCheckpoint, &TrainerTiming::checkpoint_s},
      {kLogging, &TrainerTiming::logging_s},        {kOther, &TrainerTiming::other_s}};
  // The actors' mean. The host takes the rollouts in, learns inline, evaluates,
  // checkpoints and logs while they wait: that moves from their waiting to its phases.
  std::array<Clock::duration, kPhases> spent{};
  const auto n = static_cast<Clock::rep>(std::max(1, actors));
  for (int p = 0; p < kPhases; ++p) spent[p] = actor_time[p] / n;
  for (Phase p : {kHandover, kMotionUpdates, kDqn, kEvaluation, kCheckpoint, kLogging}) {
    spent[kWaiting] -= laps.spent[p];
    spent[p] += laps.spent[p];
  }
  for (const auto& [phase, field] : fields) t.*field = s(spent[phase]);
  t.learner_busy_s = s(learner_busy_);
  t.checkpoints = run_checkpoints_;
  return t;
}

bool act_and_learn(LearnerHost& host, ActorTransport& actors, const std::function<bool()>& stop) {
  const int total = host.config().trainer.total_episodes();
  while (host.state().episode < total) {
    // A stop is taken at a block's start only: a checkpoint inside a block
    // could not be resumed to the numbers of an uninterrupted run.
    if (stop()) return false;
    const int first = host.state().episode;
    host.begin_block();
    bool stop_said = false;
    while (host.block_active()) {
      if (actors.actors() > 1 && !stop_said && stop()) {
        std::fprintf(stderr, "stopping: the actors finish the block of episodes from %d, then the checkpoint\n",
                     first + 1);
        stop_said = true;
      }
      host.ingest(actors.round(host.weights(), host.orders()));
    }
    host.end_block();
  }
  return true;
}

}  // namespace comorph::coopt
