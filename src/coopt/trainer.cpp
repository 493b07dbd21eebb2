// The hierarchical trainer (see trainer.hpp for the loop it runs): a learner
// host and its actors on threads, driven by the acting protocol's one loop
// (coopt/acting.hpp, coopt/learner_host.hpp).
#include "coopt/trainer.hpp"

#include <torch/torch.h>

#include "coopt/actor_ranks.hpp"
#include "coopt/actor_threads.hpp"
#include "coopt/learner_host.hpp"

namespace comorph::coopt {

Trainer::Trainer(const CooptConfig& config, const std::string& run_dir, TrainerCallbacks callbacks,
                 ActorPlacement actors) {
  const bool ranks = actors == ActorPlacement::mpi_ranks;
  const int n = ranks ? mpi_actor_ranks() : config.trainer.simulation_threads;
  host_ = std::make_unique<LearnerHost>(config, run_dir, callbacks, n);
  if (ranks)
    actors_ = std::make_unique<ActorRanks>(host_->config());
  else
    actors_ = std::make_unique<ActorThreads>(host_->config(), n, callbacks.label_source);
}
// The actors first: their threads use the host's config.
Trainer::~Trainer() { actors_.reset(); }

void Trainer::resume() { host_->resume(); }
int Trainer::episodes_done() const { return host_->state().episode; }
std::int64_t Trainer::env_steps() const { return host_->state().steps; }
double Trainer::wall_s() const { return host_->wall(); }
TrainerTiming Trainer::timing() const { return host_->timing(actors_->actor_time(), actors_->actors()); }

bool Trainer::run(const std::atomic<bool>* stop) {
  LearnerHost& host = *host_;
  // run()'s time is timed, and every return (or exception) ends the laps.
  struct RunClock {
    LearnerHost& host;
    Clock::time_point start = Clock::now();
    explicit RunClock(LearnerHost& h) : host(h) { host.laps.start(); }
    ~RunClock() {
      host.laps.lap(kOther);
      host.laps.on = false;
      host.run_time += Clock::now() - start;
    }
  } run_clock(host);
  host.start_run();
  if (act_and_learn(host, *actors_, [stop] { return stop && stop->load(); })) return true;
  host.checkpoint();
  return false;
}

}  // namespace comorph::coopt
