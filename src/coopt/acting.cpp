// The acting protocol's schedules and the actor (coopt/acting.hpp).
#include "coopt/acting.hpp"

#include <torch/torch.h>

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "coopt/segment.hpp"
#include "coopt/training_state.hpp"
#include "rl/learner.hpp"
#include "rl/policy.hpp"

namespace comorph::coopt {

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
  p.random_config = p.warmup || (p.scripted && t.pilot_random_configs) ||
                    (!p.refit && !p.scripted && t.random_config_interval > 0 && episode % t.random_config_interval == 0);
  p.pilot = p.scripted || (t.pilot_labels && !p.refit);
  // The refit's sweep: episode refit_start + kCandidates g + a plays the scene
  // of episode refit_start + kCandidates g with candidate a first.
  int scene_episode = episode;
  const int into_refit = episode - t.refit_start();
  if (p.refit && into_refit < t.refit_sweep_scenes * kCandidates) {
    p.first_config = into_refit % kCandidates;
    scene_episode = episode - p.first_config;
  }
  p.spec.seed = static_cast<std::uint64_t>(t.seed) * 1000003ULL + static_cast<std::uint64_t>(scene_episode);
  p.spec.stair_height = t.stair_height;
  const task::ScenarioSpec& scenario = task::scenario_spec(t.scenario);
  p.spec.obstacles = scenario.obstacles;
  p.spec.variant = scenario.variant;
  return p;
}

// splitmix64's finalizer: nearby indices give unrelated seeds.
std::uint64_t stream_seed(int seed, int episode, int stream) {
  std::uint64_t z = (static_cast<std::uint64_t>(seed) * 1000003ULL + static_cast<std::uint64_t>(episode)) * 4ULL +
                    static_cast<std::uint64_t>(stream) + 0x9E3779B97F4A7C15ULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

int block_end(const TrainerParams& t, int from) {
  auto next_multiple = [from](int k) { return (from / k + 1) * k; };
  int end = std::min(t.total_episodes(), next_multiple(t.checkpoint_interval));
  if (t.eval_interval > 0) end = std::min(end, next_multiple(t.eval_interval));
  if (from < t.refit_start()) {
    end = std::min(end, t.refit_start());
    if (t.motion_average_episodes > 0) end = std::min(end, next_multiple(t.motion_average_interval));
  }
  return end;
}

// A round gives every actor the same simulation work, not the same steps:
// a control step costs about 60 + 128 us per module (bench_sim: 301 us for 2
// modules, 1338 for 10), so with equal steps an actor with 3 modules would
// wait for one with 9 most of the round. In units of 64 us: 2 per module + 1.
// A round is worth sync_interval steps of a 4-module chain; an actor with 2
// modules takes 1.8 times as many, one with 10 0.43 times. Module counts are
// part of the run, so this too follows the run and not the timing.
int step_cost(int modules) { return 2 * modules + 1; }
int round_quota(const TrainerParams& t) { return t.sync_interval * step_cost(4); }

int most_round_transitions(const TrainerParams& t, int actors) {
  if (actors == 1) return t.sync_interval;
  return (round_quota(t) + step_cost(kMinModules) - 1) / step_cost(kMinModules) + t.motion_n_step - 1;
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

Actor::Actor(const CooptConfig& c, int actors, const std::function<int(int, int)>& label_source)
    : config_(c), one_actor_(actors == 1), runner_(c, label_source) {
  const TrainerParams& t = c.trainer;
  agent_.motion = make_motion_policy(c, static_cast<std::uint64_t>(t.seed) + 1);
  agent_.config = make_config_policy(c, false);
  if (t.config_refit_episodes > 0) other_config_ = make_config_policy(c, true);
  configure_pilot(t, pilot_);
  allocate_transitions(c, rollout_.transitions, static_cast<std::size_t>(most_round_transitions(t, actors)));
}

void Actor::take(const ActingWeights& weights, const Orders& orders) {
  if (weights.motion_version != motion_version_) {
    agent_.motion->load_weights(weights.motion);
    motion_version_ = weights.motion_version;
  }
  if (agent_.config) {
    if (weights.config_refit != config_refit_) {
      std::swap(agent_.config, other_config_);
      config_refit_ = weights.config_refit;
      config_version_ = 0;
    }
    if (weights.config_version != config_version_) {
      agent_.config->load_weights(weights.config);
      config_version_ = weights.config_version;
    }
    agent_.config->set_counters(weights.config_counters);
    if (orders.set_config_rng) agent_.config->set_rng(orders.config_rng);
  }
  if (orders.start) {
    stair_height_m_ = orders.stair_height_m;
    first_config_ = orders.first_config;
    rng_ = orders.rng;
    agent_.motion->set_rng(orders.motion_rng);
  }
  if (orders.set_motion_counters) agent_.motion->set_counters(orders.motion_counters);
}

void Actor::hand_over(ActorLink& link) {
  laps.lap(kHandover);
  if (agent_.config) rollout_.config_rng = agent_.config->rng();
  rollout_.actor_time = laps.spent;
  const ActingWeights* weights = nullptr;
  const Orders* orders = nullptr;
  link.exchange(&rollout_, weights, orders);
  laps.lap(kWaiting);
  rollout_.clear();
  round_cost_ = 0;
  take(*weights, *orders);
  laps.lap(kHandover);
}

void Actor::serve(ActorLink& link) {
  Rollout* out = nullptr;
  try {
    while (true) {
      const ActingWeights* weights = nullptr;
      const Orders* orders = nullptr;
      laps.lap(kHandover);
      link.exchange(out, weights, orders);
      if (!laps.on) laps.start();  // timed from the run's first round (TrainerTiming)
      laps.lap(kWaiting);
      rollout_.clear();
      round_cost_ = 0;
      take(*weights, *orders);
      laps.lap(kHandover);
      out = nullptr;
      if (orders->episode < 0) continue;
      play(orders->episode, link);
      out = &rollout_;
    }
  } catch (const ActorStopped&) {
  }
  laps.lap(kWaiting);
  laps.on = false;
}

// One training episode; its end is the round's end (rollout_.ended).
void Actor::play(int episode, ActorLink& link) {
  const TrainerParams& t = config_.trainer;
  EpisodePlan plan = plan_episode(t, episode);
  if (stair_height_m_ > 0) plan.spec.stair_height = stair_height_m_;
  if (first_config_ >= 0) plan.first_config = first_config_;
  LearnHooks hooks;
  hooks.laps = &laps;
  hooks.motion = [this, &link, learning = !plan.refit](const rl::Observation& o, const rl::Action& a, float r,
                                                const rl::Observation& n, bool term, bool trunc, int steps) {
    if (!learning) return;
    agent_.motion->count(term, trunc);  // the acting side's exploration schedule
    rollout_.transitions[static_cast<std::size_t>(rollout_.stored++)].set(o, a, r, n, term, trunc, steps);
    if (one_actor_ && ++interval_ == config_.trainer.sync_interval) {
      interval_ = 0;
      hand_over(link);
    }
  };
  hooks.stepped = [this, &link](bool done) {
    ++rollout_.steps;
    if (one_actor_) return;
    round_cost_ += step_cost(runner_.env().modules());
    if (round_cost_ >= round_quota(config_.trainer) && !done) hand_over(link);
  };
  hooks.motion_greedy = plan.greedy_motion;
  if (!plan.refit && t.config_energy_weight >= 0) {
    training_r2_ = config_.env.task.r2;
    training_r2_.sigma3 = t.config_energy_weight;
    hooks.config_r2 = &training_r2_;
  }
  const double config_gamma = config_model_params(config_, plan.refit).gamma;  // the refit's own in the refit
  hooks.config = [this, &link, episode, learns = plan.config_learns, config_gamma](
                     const rl::Observation& o, const rl::Action& a, float r2, const rl::Observation& n, bool term,
                     bool trunc, int k) {
    if (!learns) return;
    bool stored = false;
    if (config_.trainer.config_target == ConfigTarget::episode_return) {
      Transition& d = episode_decisions_.emplace_back();  // 2 or 3 an episode
      d.obs = o;
      d.next = n;
      d.action = a;
      episode_decision_returns_.push_back(r2);
      if (term || trunc) {
        to_return_transitions(episode_decisions_, episode_decision_returns_, config_gamma);
        for (Transition& d : episode_decisions_) rollout_.decisions.push_back({std::move(d), 1});
        episode_decisions_.clear();
        stored = true;
      }
    } else {
      StoredDecision& sd = rollout_.decisions.emplace_back();
      sd.transition.obs = o;
      sd.transition.next = n;
      sd.transition.action = a;
      sd.transition.reward = r2;
      sd.transition.terminated = term;
      sd.transition.truncated = trunc;
      sd.k = k;
      stored = true;
    }
    rollout_.decision_logs.push_back(decision_log(episode, runner_.env().step_count(), a, r2, n, term, trunc, k));
    // One actor: the configuration model learns it before its next choice
    // (at the episode's end, the end's hand-over follows at once).
    if (one_actor_ && stored && !term && !trunc) hand_over(link);
  };
  if (plan.random_config)
    hooks.random_config = [this](const std::vector<std::uint8_t>& mask) { return random_valid_action(mask, rng_); };
  if (plan.first_config >= 0)  // the first decision forced (every candidate is valid from the full chain), then the DQN's
    hooks.random_config = [first = plan.first_config, decided = false](const std::vector<std::uint8_t>& mask) mutable {
      const int a = decided || !mask[static_cast<std::size_t>(first)] ? -1 : first;
      decided = true;
      return a;
    };
  if (plan.pilot) {
    hooks.pilot = &pilot_;
    hooks.pilot_drives = plan.scripted;
    hooks.pilot_noise = t.warmup_noise;
    hooks.pilot_rng = &rng_;
  }
  rollout_.log = runner_.play(agent_, plan.spec, true, &hooks);
  rollout_.log.episode = episode;
  rollout_.log.warmup = plan.warmup;
  rollout_.ended = true;
  interval_ = 0;  // the host hands the rest to the learner at the episode's end
  rollout_.rng = rng_;
  rollout_.motion_rng = agent_.motion->rng();
  rollout_.motion_counters = agent_.motion->counters();
  if (agent_.config) rollout_.config_rng = agent_.config->rng();
  laps.lap(kOther);
  rollout_.actor_time = laps.spent;
}

namespace {

// Plain values and vectors of them, appended in order and read back in the
// same order (one program on every rank: the same sizes and layouts).
struct ByteWriter {
  std::vector<char>& out;
  template <class T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const char* p = reinterpret_cast<const char*>(&v);
    out.insert(out.end(), p, p + sizeof(T));
  }
  template <class T>
  void put(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    put(v.size());
    const char* p = reinterpret_cast<const char*>(v.data());
    out.insert(out.end(), p, p + v.size() * sizeof(T));
  }
  void put(const std::string& s) {
    put(s.size());
    out.insert(out.end(), s.begin(), s.end());
  }
};

struct ByteReader {
  const std::vector<char>& in;
  std::size_t at = 0;
  const char* take(std::size_t n) {
    if (at + n > in.size()) throw std::runtime_error("acting protocol: a message ends early (another program version?)");
    const char* p = in.data() + at;
    at += n;
    return p;
  }
  template <class T>
  void get(T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    std::memcpy(&v, take(sizeof(T)), sizeof(T));
  }
  template <class T>
  void get(std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    std::size_t n = 0;
    get(n);
    v.resize(n);
    if (n > 0) std::memcpy(v.data(), take(n * sizeof(T)), n * sizeof(T));
  }
  void get(std::string& s) {
    std::size_t n = 0;
    get(n);
    const char* p = take(n);
    s.assign(p, p + n);
  }
};

// One field list for both directions: put() for a writer, get() for a reader.
struct Put {
  ByteWriter w;
  template <class T>
  void operator()(const T& v) { w.put(v); }
};
struct Get {
  ByteReader r;
  template <class T>
  void operator()(T& v) { r.get(v); }
};

template <class F, class T>
void transition_fields(F& f, T& t) {
  f(t.obs.image), f(t.obs.vector), f(t.obs.valid_actions);
  f(t.next.image), f(t.next.vector), f(t.next.valid_actions);
  f(t.action.discrete), f(t.action.continuous), f(t.action.target);
  f(t.reward), f(t.terminated), f(t.truncated), f(t.steps);
}

template <class F, class L>
void episode_log_fields(F& f, L& l) {
  f(l.episode), f(l.seed), f(l.scenario), f(l.stair_height_m), f(l.obstacles), f(l.success), f(l.termination);
  f(l.time_s), f(l.energy_J), f(l.distance_fraction), f(l.return_R1), f(l.configurations), f(l.modules_total);
  f(l.stairs_climbed), f(l.action_saturation);
  f(l.return_R2), f(l.F), f(l.steps), f(l.switches), f(l.stairs_energy_J), f(l.first_segment_R2);
  f(l.first_segment_R1), f(l.first_segment_steps), f(l.warmup);
}

template <class F, class R>
void rollout_head_fields(F& f, R& r) {
  f(r.stored), f(r.steps), f(r.decision_logs), f(r.ended), f(r.rng), f(r.motion_rng), f(r.config_rng);
  f(r.motion_counters), f(r.actor_time);
}

// A release: these, then the two weight buffers.
template <class F, class W, class O>
void release_fields(F& f, W& w, O& o) {
  f(w.motion_version), f(w.config_version), f(w.config_refit), f(w.config_counters);
  f(o.episode), f(o.start), f(o.rng), f(o.motion_rng), f(o.set_motion_counters), f(o.motion_counters);
  f(o.set_config_rng), f(o.config_rng), f(o.stair_height_m), f(o.first_config);
}

}  // namespace

void rollout_to_bytes(const Rollout& r, std::vector<char>& bytes) {
  bytes.clear();
  Put f{{bytes}};
  rollout_head_fields(f, r);
  for (int i = 0; i < r.stored; ++i) transition_fields(f, r.transitions[static_cast<std::size_t>(i)]);
  f(r.decisions.size());
  for (const StoredDecision& d : r.decisions) {
    transition_fields(f, d.transition);
    f(d.k);
  }
  if (r.ended) episode_log_fields(f, r.log);
}

void rollout_from_bytes(const std::vector<char>& bytes, Rollout& r) {
  Get f{{bytes}};
  rollout_head_fields(f, r);
  if (r.stored > static_cast<int>(r.transitions.size()))
    throw std::runtime_error("acting protocol: a rollout of " + std::to_string(r.stored) +
                             " transitions, more than a round holds (another config?)");
  for (int i = 0; i < r.stored; ++i) transition_fields(f, r.transitions[static_cast<std::size_t>(i)]);
  std::size_t decisions = 0;
  f(decisions);
  r.decisions.resize(decisions);
  for (StoredDecision& d : r.decisions) {
    transition_fields(f, d.transition);
    f(d.k);
  }
  if (r.ended) episode_log_fields(f, r.log);
}

void release_to_bytes(const ActingWeights& w, const Orders& o, bool motion_weights, bool config_weights,
                      std::vector<char>& bytes) {
  static const std::vector<float> none;
  bytes.clear();
  Put f{{bytes}};
  release_fields(f, w, o);
  f(motion_weights ? w.motion : none), f(config_weights ? w.config : none);
}

// An empty buffer stands for the version the actor holds (Actor::take reads
// the buffers only for a new version).
void release_from_bytes(const std::vector<char>& bytes, ActingWeights& w, Orders& o) {
  Get f{{bytes}};
  release_fields(f, w, o);
  f(w.motion), f(w.config);
}

}  // namespace comorph::coopt
