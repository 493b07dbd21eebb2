// The acting protocol's transport between threads of one process
// (coopt/acting.hpp): each actor on a thread of its own, the host on the
// caller's. A round: the host publishes the weights and orders and releases
// the actors; each actor with an episode plays its round and arrives with
// its rollout; the host reads them when all have arrived. The values are
// shared, not copied: while the actors play, the host waits, and the other
// way round. Internal to coopt.
#pragma once

#include <condition_variable>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "coopt/acting.hpp"

namespace comorph::coopt {

class ActorThreads final : public ActorTransport {
 public:
  ActorThreads(const CooptConfig& c, int actors, const std::function<int(int, int)>& label_source);
  ~ActorThreads() override;  // stops and joins the threads
  int actors() const override { return static_cast<int>(slots_.size()); }
  std::vector<Rollout*>& round(const ActingWeights& weights, const std::vector<Orders>& orders) override;
  std::array<Clock::duration, kPhases> actor_time() const override;

 private:
  struct Slot;
  class Link;
  std::vector<std::unique_ptr<Slot>> slots_;
  std::vector<Rollout*> rollouts_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::uint64_t generation_ = 0;  // bumped at each release
  int arrived_ = 0;
  bool quit_ = false;
  std::exception_ptr error_;  // the first exception of an actor
  const ActingWeights* weights_ = nullptr;
  const std::vector<Orders>* orders_ = nullptr;
};

}  // namespace comorph::coopt
