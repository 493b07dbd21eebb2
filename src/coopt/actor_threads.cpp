#include "coopt/actor_threads.hpp"

#include <torch/torch.h>

namespace comorph::coopt {

class ActorThreads::Link final : public ActorLink {
 public:
  Link(ActorThreads& threads, int index) : threads_(threads), index_(index) {}
  void exchange(Rollout* rollout, const ActingWeights*& weights, const Orders*& orders) override {
    ActorThreads& t = threads_;
    std::unique_lock<std::mutex> lock(t.mutex_);
    if (rollout) {
      t.rollouts_[static_cast<std::size_t>(index_)] = rollout;
      ++t.arrived_;
      t.cv_.notify_all();
    }
    t.cv_.wait(lock, [&] { return t.generation_ != generation_ || t.quit_; });
    if (t.quit_) throw ActorStopped{};
    generation_ = t.generation_;
    weights = t.weights_;
    orders = &(*t.orders_)[static_cast<std::size_t>(index_)];
  }

 private:
  ActorThreads& threads_;
  int index_;
  std::uint64_t generation_ = 0;  // the last release it saw
};

struct ActorThreads::Slot {
  Slot(const CooptConfig& c, int actors, const std::function<int(int, int)>& label_source, ActorThreads& threads,
       int index)
      : actor(c, actors, label_source), link(threads, index) {}
  Actor actor;
  Link link;
  std::thread thread;
};

ActorThreads::ActorThreads(const CooptConfig& c, int actors, const std::function<int(int, int)>& label_source) {
  rollouts_.assign(static_cast<std::size_t>(actors), nullptr);
  for (int i = 0; i < actors; ++i) slots_.push_back(std::make_unique<Slot>(c, actors, label_source, *this, i));
  for (auto& s : slots_)
    s->thread = std::thread([this, s = s.get()] {
      try {
        s->actor.serve(s->link);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!error_) error_ = std::current_exception();
        cv_.notify_all();
      }
    });
}

ActorThreads::~ActorThreads() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    quit_ = true;
  }
  cv_.notify_all();
  for (auto& s : slots_)
    if (s->thread.joinable()) s->thread.join();
}

std::vector<Rollout*>& ActorThreads::round(const ActingWeights& weights, const std::vector<Orders>& orders) {
  int active = 0;
  std::unique_lock<std::mutex> lock(mutex_);
  weights_ = &weights;
  orders_ = &orders;
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    rollouts_[i] = nullptr;
    active += orders[i].episode >= 0;
  }
  arrived_ = 0;
  ++generation_;
  cv_.notify_all();
  cv_.wait(lock, [&] { return arrived_ == active || error_; });
  if (error_) std::rethrow_exception(error_);
  return rollouts_;
}

std::array<Clock::duration, kPhases> ActorThreads::actor_time() const {
  std::array<Clock::duration, kPhases> spent{};
  for (const auto& s : slots_)
    for (int p = 0; p < kPhases; ++p) spent[p] += s->actor.laps.spent[p];
  return spent;
}

}  // namespace comorph::coopt
