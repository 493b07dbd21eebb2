// The acting protocol's transport between the ranks of an MPI job
// (coopt/acting.hpp): rank 0 is the learner host, ranks 1..K-1 are actors.
// A round: the host sends each actor rank the weights and its orders as one
// message, then receives the rollout of each actor with an episode as they
// arrive, and hands them on in actor order (the values as bytes:
// rollout_to_bytes, release_to_bytes). Sends do not block and waiting polls
// with growing sleeps, so a waiting rank leaves its core to the others.
// Internal to coopt; the public face is coopt/trainer.hpp (MpiJob,
// ActorPlacement, serve_actor_rank).
#pragma once

#include <mpi.h>

#include <vector>

#include "coopt/acting.hpp"

namespace comorph::coopt {

// The job's actor ranks (its size - 1); throws outside an MPI job.
int mpi_actor_ranks();

class ActorRanks final : public ActorTransport {
 public:
  // The job's other ranks; the job is joined (MpiJob).
  explicit ActorRanks(const CooptConfig& c);
  ~ActorRanks() override;  // tells every actor rank that the run ended
  int actors() const override { return static_cast<int>(rollouts_.size()); }
  std::vector<Rollout*>& round(const ActingWeights& weights, const std::vector<Orders>& orders) override;
  // As of each actor's latest rollout.
  std::array<Clock::duration, kPhases> actor_time() const override;

 private:
  std::vector<Rollout> received_;  // by actor, preallocated
  // The weights' versions each actor holds: it is sent only newer ones.
  std::vector<std::uint64_t> motion_version_, config_version_;
  std::vector<Rollout*> rollouts_;
  std::vector<char> bytes_;
  std::vector<std::vector<char>> releases_;  // by actor: in flight until every send is done
  std::vector<MPI_Request> sends_;
  Clock::duration last_round_{};  // from the releases to the last rollout
};

}  // namespace comorph::coopt
