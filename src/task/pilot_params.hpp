// The scripted pilot's settings (task::ScriptedPilot): plain data, so that
// configs can name them without the simulator's headers.
#pragma once

#include <array>
#include <optional>

#include "common/enum_names.hpp"
#include "morphology/configuration.hpp"  // kMaxModules

namespace comorph::task {

struct StairGait {  // stair-mode action (Eq. 4/5 inputs), held while climbing
  float speed = 1.0f;       // a0
  float amp_front = 0.0f;   // a2 (-1 = no wave)
  float phase = 0.5f;       // a3
  float amp_back = 0.0f;    // a4
};

// How the pilot steers on the flat area.
enum class FlatSteering : int { planned = 0, scan = 1 };
constexpr auto enum_names(FlatSteering) {
  return std::array{EnumName{FlatSteering::planned, "planned"}, EnumName{FlatSteering::scan, "scan"}};
}

// How the pilot steers while climbing: straight up the middle of the stairs,
// or around what the obstacle scan shows on the treads (the mixed variant).
enum class StairSteering : int { straight = 0, scan = 1 };
constexpr auto enum_names(StairSteering) {
  return std::array{EnumName{StairSteering::straight, "straight"}, EnumName{StairSteering::scan, "scan"}};
}

struct PilotParams {
  StairGait gait;               // used in stair mode (unless gait_by_modules has one for the chain)
  // Per chain length (index = modules), a gait of its own where set. One gait
  // does not suit every length: the wave lag that climbs with 2, 4 or 6
  // modules stalls 3 modules on the first riser (searched_stair_gaits()).
  std::array<std::optional<StairGait>, kMaxModules + 1> gait_by_modules{};
  double heading_gain = 2.5;    // a1 per rad of heading error
  double lookahead = 0.6;       // m along the planned path
  double clearance = 0.40;      // m, obstacles inflated by this when planning
  double slow_turn_error = 0.6; // rad: above this heading error the robot turns before driving
  FlatSteering flat_steering = FlatSteering::planned;
  // FlatSteering::scan (needs RobotParams::scan_columns > 0). A bearing is
  // open when no scanned point lies in the corridor of half-width
  // scan_corridor_m along it, up to scan_lookahead_m (or the goal). The pilot
  // aims at the goal when its bearing is open, else at the open ray bearing
  // nearest the goal. Bearings on the other side than the last turn (the
  // state's previous action, when its |a1| exceeds scan_committed_turn) cost
  // scan_hysteresis_rad more: with an obstacle
  // straight ahead both sides are equally near the goal while turning in
  // place, and without it a memoryless controller alternates between them.
  // Above scan_slow_turn_error of heading error it turns before driving (its
  // targets lie off the heading more often than the planned path's).
  // Chosen with `comorph demo --pilot-steering scan --noise 0.2 --max-steps
  // 2000` over 24 seeds each of 6 / 4 / 2 modules at 0.08 / 0.06 / 0.04 m:
  // 66 of 72 reach the target (corridor 0.4, lookahead 1.2, 0.6 rad: 62).
  double scan_corridor_m = 0.3;
  double scan_lookahead_m = 0.9;
  double scan_hysteresis_rad = 2.0;
  double scan_committed_turn = 0.2;  // |a1| of the last turn that counts as a side
  double scan_slow_turn_error = 1.0;
  // StairSteering::scan (needs the scan too). Climbing, the level scan also
  // hits the risers (a wall across the whole fan, or its rays one by one, 0.1 m
  // apart and more) and, when the module pitches down, the tread ahead. An
  // obstacle is a run of at least 2 adjacent rays whose points lie within
  // stair_point_gap_m of each other and span at most stair_obstacle_max_m
  // (a 0.3 m box: 0.2 to 0.3 m; a riser's run spans 0.6 m and more). The
  // pilot keeps its lane (drives along the stairs) unless such a run lies in
  // the corridor ahead up to stair_lookahead_m; then it aims at the open
  // bearing nearest the stairs' direction, as on the flat area. It returns to
  // the middle only beyond stair_lane_m from it.
  StairSteering stair_steering = StairSteering::straight;
  double stair_point_gap_m = 0.12;
  double stair_obstacle_max_m = 0.45;
  double stair_lookahead_m = 1.0;
  double stair_lane_m = 0.5;
};

// The pilot with the stair gaits of a search over a0 x a2=a4 x a3 per chain
// length (docs/history.md): the shared gait, and 3 modules' own.
PilotParams searched_stair_gaits();

}  // namespace comorph::task
