#include "coopt/actor_ranks.hpp"

#include <mpi.h>
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <thread>

#include "rl/learner.hpp"

namespace comorph::coopt {
namespace {

enum Tag { kRelease = 1, kRollout = 2, kStop = 3 };

void check(int code, const char* what) {
  if (code != MPI_SUCCESS) throw std::runtime_error(std::string("MPI: ") + what + " failed");
}

// Waits for a message from `source` (MPI_ANY_SOURCE: any rank) with `tag`
// (MPI_ANY_TAG: any) without spinning on the core (MPI's blocking receive
// polls it at 100 %): sleeps from 20 us, doubling up to `longest`, and up to
// 100 us once `due` has passed. The host waits a whole round for rollouts
// (1 ms: a wake-up a millisecond) until the time the last round took is
// nearly up; an actor waits while the host closes the round, and its
// wake-up delays the next round (200 us).
MPI_Status wait_for_message(int source, int tag, std::chrono::microseconds longest,
                            Clock::time_point due = Clock::time_point::max()) {
  constexpr std::chrono::microseconds kWhenDue(100);
  MPI_Status status;
  int arrived = 0;
  auto nap = std::chrono::microseconds(20);
  while (true) {
    check(MPI_Iprobe(source, tag, MPI_COMM_WORLD, &arrived, &status), "MPI_Iprobe");
    if (arrived) return status;
    const auto most = Clock::now() < due ? longest : std::min(longest, kWhenDue);
    nap = std::min(nap, most);
    std::this_thread::sleep_for(nap);
    nap = std::min(2 * nap, most);
  }
}

void receive(int source, const MPI_Status& status, std::vector<char>& bytes) {
  int size = 0;
  check(MPI_Get_count(&status, MPI_BYTE, &size), "MPI_Get_count");
  bytes.resize(static_cast<std::size_t>(size));
  check(MPI_Recv(bytes.data(), size, MPI_BYTE, source, status.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE), "MPI_Recv");
}

// An actor rank's side: the host is rank 0.
class RankLink final : public ActorLink {
 public:
  void exchange(Rollout* rollout, const ActingWeights*& weights, const Orders*& orders) override {
    // The rollout goes without blocking: a message this size waits for the
    // host's receive (rendezvous), and a blocking send would spin this core
    // until then, away from the other actors and the learner.
    MPI_Request sent = MPI_REQUEST_NULL;
    if (rollout) {
      rollout_to_bytes(*rollout, rollout_bytes_);
      check(MPI_Isend(rollout_bytes_.data(), static_cast<int>(rollout_bytes_.size()), MPI_BYTE, 0, kRollout,
                      MPI_COMM_WORLD, &sent),
            "MPI_Isend");
    }
    const MPI_Status status = wait_for_message(0, MPI_ANY_TAG, std::chrono::microseconds(200));
    receive(0, status, release_bytes_);
    // The host releases a round only after it received every rollout: done.
    check(MPI_Wait(&sent, MPI_STATUS_IGNORE), "MPI_Wait");
    if (status.MPI_TAG == kStop) throw ActorStopped{};
    release_from_bytes(release_bytes_, weights_, orders_);
    weights = &weights_;
    orders = &orders_;
  }

 private:
  std::vector<char> rollout_bytes_, release_bytes_;
  ActingWeights weights_;
  Orders orders_;
};

}  // namespace

MpiJob::MpiJob() {
  // mpirun (OpenMPI) names the job's size; a program started alone stays out of MPI.
  const char* size = std::getenv("OMPI_COMM_WORLD_SIZE");
  if (!size || std::atoi(size) < 2) return;
  int provided = 0;
  check(MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
  check(MPI_Comm_rank(MPI_COMM_WORLD, &rank_), "MPI_Comm_rank");
  check(MPI_Comm_size(MPI_COMM_WORLD, &size_), "MPI_Comm_size");
}

MpiJob::~MpiJob() {
  if (size_ > 1) MPI_Finalize();
}

void MpiJob::abort(int code) const {
  std::fflush(stderr);
  MPI_Abort(MPI_COMM_WORLD, code);
}

int mpi_actor_ranks() {
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (!initialized) throw std::logic_error("actors on MPI ranks: this process is not part of an MPI job (mpirun)");
  int size = 0;
  check(MPI_Comm_size(MPI_COMM_WORLD, &size), "MPI_Comm_size");
  return size - 1;
}

ActorRanks::ActorRanks(const CooptConfig& c) : received_(static_cast<std::size_t>(mpi_actor_ranks())) {
  rollouts_.assign(received_.size(), nullptr);
  motion_version_.assign(received_.size(), 0);
  releases_.resize(received_.size());
  sends_.resize(received_.size());
  config_version_.assign(received_.size(), 0);
  const int most = most_round_transitions(c.trainer, actors());
  for (Rollout& r : received_) allocate_transitions(c, r.transitions, static_cast<std::size_t>(most));
}

ActorRanks::~ActorRanks() {
  const std::vector<char> none;
  for (int rank = 1; rank <= actors(); ++rank) MPI_Send(none.data(), 0, MPI_BYTE, rank, kStop, MPI_COMM_WORLD);
}

std::vector<Rollout*>& ActorRanks::round(const ActingWeights& weights, const std::vector<Orders>& orders) {
  // All releases at once: each actor takes its own as soon as it wakes, not
  // after the one before it.
  for (std::size_t i = 0; i < received_.size(); ++i) {
    const bool motion = motion_version_[i] != weights.motion_version;
    const bool config = config_version_[i] != weights.config_version;
    release_to_bytes(weights, orders[i], motion, config, releases_[i]);
    check(MPI_Isend(releases_[i].data(), static_cast<int>(releases_[i].size()), MPI_BYTE, static_cast<int>(i) + 1,
                    kRelease, MPI_COMM_WORLD, &sends_[i]),
          "MPI_Isend");
    motion_version_[i] = weights.motion_version;
    config_version_[i] = weights.config_version;
  }
  // The rollouts in the order they arrive (each actor's send waits for this
  // receive), each into its actor's place: the round's order is the actors'.
  int expected = 0;
  for (std::size_t i = 0; i < received_.size(); ++i) {
    rollouts_[i] = nullptr;
    expected += orders[i].episode >= 0;
  }
  // Short naps from 90 % of the last round's time on: a 1 ms nap would
  // overshoot a rollout's arrival by 0.5 ms on average, 1.5 % of a round.
  const Clock::time_point released = Clock::now();
  const Clock::time_point due = released + last_round_ * 9 / 10;
  for (; expected > 0; --expected) {
    const MPI_Status status = wait_for_message(MPI_ANY_SOURCE, kRollout, std::chrono::microseconds(1000), due);
    receive(status.MPI_SOURCE, status, bytes_);
    const auto i = static_cast<std::size_t>(status.MPI_SOURCE - 1);
    if (rollouts_[i]) throw std::logic_error("actor rank " + std::to_string(i + 1) + " sent two rollouts in a round");
    rollout_from_bytes(bytes_, received_[i]);
    rollouts_[i] = &received_[i];
  }
  last_round_ = Clock::now() - released;
  // Done by now (the probes above moved them on): the buffers are free again.
  check(MPI_Waitall(static_cast<int>(sends_.size()), sends_.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
  return rollouts_;
}

std::array<Clock::duration, kPhases> ActorRanks::actor_time() const {
  std::array<Clock::duration, kPhases> spent{};
  for (const Rollout& r : received_)
    for (int p = 0; p < kPhases; ++p) spent[p] += r.actor_time[p];
  return spent;
}

void serve_actor_rank(const CooptConfig& config, const std::function<int(int, int)>& label_source) {
  rl::set_torch_threads(config.trainer.torch_threads, 1);  // as the host's process sets its own (TrainingState)
  Actor actor(config, mpi_actor_ranks(), label_source);
  RankLink link;
  actor.serve(link);
}

}  // namespace comorph::coopt
