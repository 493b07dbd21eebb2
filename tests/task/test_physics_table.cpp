// Ordering properties of the physics table on a reduced set of trials: the
// trade-off the paper's configuration choice depends on.
#include <gtest/gtest.h>

#include "task/physics_table.hpp"
#include "task/scripted_pilot.hpp"

using namespace comorph;

namespace {
const task::StairGait kWave{1.0f, 1.0f, -0.5f, 1.0f};  // the gait the search picks
}

TEST(PhysicsTable, TwoModulesClimbLowStepsOnly) {
  const task::EnvConfig c;
  const task::PhysicsTableOptions o;
  EXPECT_TRUE(task::run_climb_trial(c, 2, 0.04, 1, kWave, o).climbed);
  // 0.08 m: no gait of the search grid gets two modules up.
  for (float amp : o.amplitudes)
    for (float phase : o.phases)
      EXPECT_FALSE(task::run_climb_trial(c, 2, 0.08, 1, {1.0f, amp, phase, amp}, o).climbed)
          << amp << " " << phase;
}

TEST(PhysicsTable, SixModulesClimbHighStepsAndSpendMore) {
  const task::EnvConfig c;
  const task::PhysicsTableOptions o;
  const task::ClimbTrial six_high = task::run_climb_trial(c, 6, 0.08, 1, kWave, o);
  EXPECT_TRUE(six_high.climbed);
  const task::ClimbTrial two_low = task::run_climb_trial(c, 2, 0.04, 2, kWave, o);
  const task::ClimbTrial six_low = task::run_climb_trial(c, 6, 0.04, 2, kWave, o);
  ASSERT_TRUE(two_low.climbed);
  ASSERT_TRUE(six_low.climbed);
  EXPECT_GT(six_low.energy_J, 1.5 * two_low.energy_J);
  EXPECT_GT(six_high.energy_J, six_low.energy_J);  // higher steps cost more
}

TEST(PhysicsTable, TurningGetsHarderWithLength) {
  const task::EnvConfig c;
  const double two = task::measure_turn_rate(c, 2, 2.0);
  const double six = task::measure_turn_rate(c, 6, 2.0);
  const double ten = task::measure_turn_rate(c, 10, 2.0);
  EXPECT_GT(two, 0.0);  // a1 > 0 turns left
  EXPECT_GT(two, 2 * six);
  EXPECT_GT(six, ten);
}

// One gait does not suit every length: the lag that climbs with 2, 4 and 6
// modules stalls 3 modules on the first riser; the per-length table's gait
// gets them up (task::searched_stair_gaits).
TEST(PhysicsTable, ThreeModulesNeedTheirOwnGait) {
  const task::EnvConfig c;
  const task::PhysicsTableOptions o;
  const task::PilotParams p = task::searched_stair_gaits();
  ASSERT_TRUE(p.gait_by_modules[3].has_value());
  for (std::uint64_t seed : {1, 2}) {
    EXPECT_FALSE(task::run_climb_trial(c, 3, 0.04, seed, kWave, o).climbed) << seed;
    EXPECT_TRUE(task::run_climb_trial(c, 3, 0.04, seed, *p.gait_by_modules[3], o).climbed) << seed;
  }
}
