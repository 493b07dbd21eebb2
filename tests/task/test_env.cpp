// MultiTaskEnv: determinism, observation layout, events, termination reasons, reconfiguration.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "task/multitask_env.hpp"
#include "task/scripted_pilot.hpp"

using namespace comorph;
using task::Termination;

namespace {

// Deterministic pseudo-random actions in [-1, 1].
struct Lcg {
  std::uint64_t s = 12345;
  float next() {
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    return float(double(s >> 11) / 9007199254740992.0 * 2.0 - 1.0);
  }
};

task::EpisodeSpec spec(std::uint64_t seed, int modules, double h = 0, int k = -1) {
  task::EpisodeSpec s;
  s.seed = seed;
  s.configuration = make_chain(modules);
  s.stair_height = h;
  s.obstacles = k;
  return s;
}

// One episode of `s` driven by the pilot (planned first); how it ended.
Termination pilot_episode(task::MultiTaskEnv& env, task::ScriptedPilot& pilot, const task::EpisodeSpec& s) {
  env.reset(s);
  pilot.plan(env);
  float a[5];
  control::MotionMode mode;
  while (!env.done()) {
    pilot.act(env, a, mode);
    env.step(a, mode);
  }
  return env.last().reason;
}

}  // namespace

TEST(Env, SameSeedAndActionsGiveTheSameTrajectory) {
  const task::EnvConfig c;
  task::MultiTaskEnv a(c), b(c);
  a.reset(spec(5, 6));
  b.reset(spec(5, 6));
  Lcg rng;
  const int pixels = a.depth_width() * a.depth_height();
  for (int t = 0; t < 150 && !a.done(); ++t) {
    float action[5];
    for (float& x : action) x = rng.next();
    const auto mode = t % 50 < 25 ? control::MotionMode::stair : control::MotionMode::flat;
    const double ra = a.step(action, mode).reward, rb = b.step(action, mode).reward;
    ASSERT_EQ(ra, rb) << t;
    for (int i = 0; i < task::obs::kStateSize; ++i) ASSERT_EQ(a.state()[i], b.state()[i]) << t << " " << i;
    for (int i = 0; i < pixels; ++i) ASSERT_EQ(a.depth()[i], b.depth()[i]) << t;
    ASSERT_EQ(a.done(), b.done());
  }
  // Reusing an env (same cached models) reproduces the same trajectory too.
  a.reset(spec(5, 6));
  task::MultiTaskEnv fresh(c);
  fresh.reset(spec(5, 6));
  Lcg rng2;
  for (int t = 0; t < 60; ++t) {
    float action[5];
    for (float& x : action) x = rng2.next();
    a.step(action, control::MotionMode::stair);
    fresh.step(action, control::MotionMode::stair);
    ASSERT_EQ(a.world().data()->qpos[0], fresh.world().data()->qpos[0]) << t;
  }
}

TEST(Env, ObservationLayout) {
  task::EnvConfig c;
  task::MultiTaskEnv env(c);
  env.reset(spec(2, 4));
  const float* s = env.state();
  EXPECT_FLOAT_EQ(s[task::obs::kBattery], 1.0f);
  EXPECT_NEAR(s[task::obs::kPosition], env.world().module_pos(0)[0], 1e-6);
  EXPECT_NEAR(s[task::obs::kPosition + 2], c.robot.wheel_radius, 1e-3);
  for (int k = 0; k < 10; ++k) EXPECT_EQ(s[task::obs::kModuleMask + k], k < 4 ? 1.0f : 0.0f);
  for (int k = 4; k < 10; ++k) EXPECT_EQ(s[task::obs::kDistances + 2 * k], 0.0f);
  EXPECT_GT(s[task::obs::kGoal], 0.9f);  // facing the stairs goal
  EXPECT_EQ(s[task::obs::kMode], float(int(control::MotionMode::stair)));
  EXPECT_EQ(env.scene_label(), sim::kLabelStairs);
  const float a[5] = {1.0f, 0.2f, -1.0f, 0.0f, -1.0f};
  for (int t = 0; t < 30; ++t) env.step(a, control::MotionMode::flat);
  s = env.state();
  for (int i = 0; i < 5; ++i) EXPECT_EQ(s[task::obs::kPrevAction + i], a[i]);
  EXPECT_EQ(s[task::obs::kPrevReward], float(env.last().reward));
  EXPECT_GT(s[task::obs::kVelocity], 0.05f);   // driving towards +x
  EXPECT_LT(s[task::obs::kBattery], 1.0f);
  EXPECT_EQ(s[task::obs::kMode], float(int(control::MotionMode::flat)));
  EXPECT_GT(env.last().reward, 0.0);  // progress towards the goal pays
  for (int i = 0; i < env.depth_width() * env.depth_height(); ++i) {
    EXPECT_GE(env.depth()[i], 0.01f);
    EXPECT_LE(env.depth()[i], 1.0f);
  }
}

// The declared spec sizes every observation buffer and bounds its values.
TEST(Env, SpecDeclaresTheObservationsAndTheAction) {
  for (int scan : {0, 24}) {
    task::EnvConfig c;
    c.robot.scan_columns = scan;
    task::MultiTaskEnv env(c);
    const task::EnvSpec s = env.spec();
    EXPECT_EQ(s.depth_channels * s.depth_height * s.depth_width, env.depth_width() * env.depth_height());
    EXPECT_EQ(s.state_size, task::obs::kStateSize);
    EXPECT_EQ(s.clearance_size, scan > 0 ? scan : c.robot.depth_width);
    EXPECT_EQ(s.clearance_size, env.clearance_width());
    EXPECT_EQ(s.decision_depth_width * s.decision_depth_height,
              env.decision_depth_width() * env.decision_depth_height());
    EXPECT_EQ(s.action_size, control::kActionSize);
    EXPECT_EQ(s.min_modules, 2);
    EXPECT_EQ(s.max_modules, 10);
    env.reset(spec(3, 5));
    const float a[5] = {1.0f, 0.5f, 0.0f, 0.0f, 0.0f};
    for (int t = 0; t < 20; ++t) env.step(a);
    for (int i = 0; i < s.depth_height * s.depth_width; ++i) {
      EXPECT_GE(env.depth()[i], s.depth_low);
      EXPECT_LE(env.depth()[i], s.depth_high);
    }
    for (int i = 0; i < s.clearance_size; ++i) {
      EXPECT_GE(env.clearance()[i], s.depth_low);
      EXPECT_LE(env.clearance()[i], s.depth_high);
    }
  }
}

// Steering by the obstacle scan alone (what the motion model sees) must get
// through the obstacle field: a wrong sign, a wrong ray order or the dithering
// between two sides it prevents would leave it stuck or hit the boxes.
TEST(Env, ScanSteeredPilotCrossesTheObstacleField) {
  task::EnvConfig c;
  c.robot.scan_columns = 24;
  task::MultiTaskEnv env(c);
  task::ScriptedPilot pilot(task::searched_stair_gaits());
  pilot.params().flat_steering = task::FlatSteering::scan;
  int successes = 0, collisions = 0;
  for (int modules : {2, 4})
    for (std::uint64_t seed = 100; seed < 106; ++seed) {
      const Termination reason = pilot_episode(env, pilot, spec(seed, modules, 0.04));
      successes += reason == Termination::success;
      collisions += reason == Termination::collision;
    }
  EXPECT_GE(successes, 11) << collisions << " collisions";
}

// In the mixed variant two obstacles stand on the treads. A 2-module chain
// turns in stair mode; steering around what the scan shows there
// (StairSteering::scan) must reach the target clearly more often than
// climbing straight up the middle, which hits them (demo seeds 500..523:
// 15 against 9 of 24). Risers must not count as obstacles, or it would turn
// away from the stairs and lose episodes instead.
TEST(Env, StairScanSteeringAvoidsObstaclesOnTheTreads) {
  task::EnvConfig c;
  c.robot.scan_columns = 24;
  task::MultiTaskEnv env(c);
  auto successes = [&](task::StairSteering steering) {
    task::ScriptedPilot pilot(task::searched_stair_gaits());
    pilot.params().flat_steering = task::FlatSteering::scan;
    pilot.params().stair_steering = steering;
    int n = 0;
    for (std::uint64_t seed = 500; seed < 524; ++seed) {
      task::EpisodeSpec s = spec(seed, 2, 0.04);
      s.variant = sim::Variant::mixed;
      n += pilot_episode(env, pilot, s) == Termination::success;
    }
    return n;
  };
  const int straight = successes(task::StairSteering::straight), scan = successes(task::StairSteering::scan);
  EXPECT_GE(scan, straight + 4) << "straight " << straight << ", scan " << scan << " of 24";
}

TEST(Env, ScanSteeringNeedsTheScan) {
  task::MultiTaskEnv env(task::EnvConfig{});  // scan_columns 0
  env.reset(spec(1, 2, 0.04));
  task::ScriptedPilot pilot(task::searched_stair_gaits());  // climbs, so that it reaches the flat area
  pilot.params().flat_steering = task::FlatSteering::scan;
  pilot.plan(env);
  float a[5];
  control::MotionMode mode;
  EXPECT_THROW(
      while (!env.done()) {
        pilot.act(env, a, mode);
        env.step(a, mode);
      },
      std::logic_error);
}

TEST(Env, ScriptedRunClimbsReachesTheTargetAndReportsEvents) {
  const task::EnvConfig c;
  task::MultiTaskEnv env(c);
  env.reset(spec(1, 4));
  task::ScriptedPilot pilot;
  pilot.params().gait = {1.0f, 1.0f, -0.5f, 1.0f};
  pilot.plan(env);
  std::vector<int> labels{env.scene_label()};
  int climbed_events = 0;
  double energy = 0;
  float a[5];
  control::MotionMode mode;
  while (!env.done()) {
    pilot.act(env, a, mode);
    const task::StepOutcome& r = env.step(a, mode);
    energy += r.energy_J;
    climbed_events += r.stairs_climbed_now;
    if (r.scene_label != labels.back()) labels.push_back(r.scene_label);
  }
  EXPECT_EQ(env.last().reason, Termination::success);
  EXPECT_TRUE(env.last().terminated);
  EXPECT_EQ(climbed_events, 1);
  EXPECT_GT(env.stairs_climbed_step(), 0);
  EXPECT_GT(env.stairs_energy(), 0.0);
  EXPECT_LT(env.stairs_energy(), energy);
  EXPECT_EQ(labels, (std::vector<int>{0, 1, 2}));
  const task::EpisodeMetrics m = env.metrics();
  EXPECT_NEAR(m.energy_J, energy, 1e-6);
  EXPECT_NEAR(m.E, energy / 20000.0, 1e-12);
  EXPECT_GT(m.D, 0.9);
  EXPECT_NEAR(m.T, m.steps * 0.032 / 120.0, 1e-12);
  EXPECT_NEAR(m.F, -m.T - 2 * m.E + 2 * m.D, 1e-12);
  // Calibration: a competent run draws about 27 W per module.
  const double watts = m.energy_J / m.time_s / 4;
  EXPECT_GT(watts, 22.0);
  EXPECT_LT(watts, 32.0);
  float x[5] = {};
  EXPECT_THROW(env.step(x), std::logic_error);
}

TEST(Env, FailureStatesEndTheEpisodeWithTheirReason) {
  const task::EnvConfig c;
  task::MultiTaskEnv env(c);
  const float forward[5] = {1.0f, 0.0f, -1.0f, 0.0f, -1.0f};

  // Leaving the stair lane sideways.
  env.reset(spec(3, 3));
  mjData* d = env.mutable_world().mutable_data();
  d->qpos[1] = 1.2;
  mj_forward(env.world().model(), d);
  const task::StepOutcome& left = env.step(forward, control::MotionMode::flat);
  EXPECT_TRUE(left.terminated);
  EXPECT_EQ(left.reason, Termination::left_area);
  EXPECT_LT(left.reward, -5.0);  // r_u

  // Physics blow-up.
  env.reset(spec(3, 3));
  env.mutable_world().mutable_data()->qvel[2] = std::nan("");
  EXPECT_EQ(env.step(forward, control::MotionMode::flat).reason, Termination::physics_unstable);

  // Driving into an obstacle on the flat area.
  env.reset(spec(3, 3, 0.04, 6));
  const sim::SceneLayout& s = env.world().layout();
  const sim::Box& o = s.obstacles[0];
  d = env.mutable_world().mutable_data();
  d->qpos[0] = o.x - o.hx - 0.2;
  d->qpos[1] = o.y;
  d->qpos[2] = s.platform_z + c.robot.wheel_radius + 0.005;
  d->qpos[3] = 1;
  d->qpos[4] = d->qpos[5] = d->qpos[6] = 0;
  mj_forward(env.world().model(), d);
  Termination reason = Termination::none;
  for (int t = 0; t < 100 && !env.done(); ++t) reason = env.step(forward, control::MotionMode::flat).reason;
  EXPECT_EQ(reason, Termination::collision);

  // Overturned: module 1 upside down.
  env.reset(spec(3, 3));
  d = env.mutable_world().mutable_data();
  d->qpos[2] = 0.3;
  d->qpos[3] = 0;
  d->qpos[4] = 1;  // 180 deg about x
  mj_forward(env.world().model(), d);
  EXPECT_EQ(env.step(forward, control::MotionMode::flat).reason, Termination::overturned);

  // Step cap truncates.
  task::EnvConfig short_cfg = c;
  short_cfg.task.max_steps = 5;
  task::MultiTaskEnv capped(short_cfg);
  capped.reset(spec(3, 2));
  const float still[5] = {0.0f, 0.0f, -1.0f, 0.0f, -1.0f};
  for (int t = 0; t < 4; ++t) EXPECT_FALSE(capped.step(still).truncated);
  const task::StepOutcome& r = capped.step(still);
  EXPECT_TRUE(r.truncated);
  EXPECT_FALSE(r.terminated);
  EXPECT_EQ(r.reason, Termination::step_cap);
}

TEST(Env, ReconfigurationMidEpisodeKeepsTheHeadAndUpdatesTheMask) {
  const task::EnvConfig c;
  task::MultiTaskEnv env(c);
  env.reset(spec(4, 6, 0.06, 6));
  const float a[5] = {1.0f, 0.0f, 0.5f, -0.5f, 0.5f};
  for (int t = 0; t < 80; ++t) env.step(a, control::MotionMode::stair);
  const double x = env.world().module_pos(0)[0], e = env.metrics().energy_J;
  const std::vector<float> dist(env.state() + task::obs::kDistances, env.state() + task::obs::kDistances + 6);
  env.reconfigure(make_chain(3));
  EXPECT_EQ(env.modules(), 3);
  EXPECT_EQ(env.initial_modules(), 6);
  EXPECT_EQ(env.world().module_pos(0)[0], x);
  EXPECT_NEAR(env.metrics().energy_J, e, 1e-9);  // shed modules still count (summed in another order)
  for (int k = 0; k < 10; ++k) EXPECT_EQ(env.state()[task::obs::kModuleMask + k], k < 3 ? 1.0f : 0.0f);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(env.state()[task::obs::kDistances + i], dist[i]);
  EXPECT_THROW(env.reconfigure(make_chain(4)), std::invalid_argument);
  for (int t = 0; t < 20; ++t) env.step(a, control::MotionMode::stair);
  EXPECT_GT(env.world().module_pos(0)[0], x);
}

TEST(Env, DatasetDepthFromArbitraryPoses) {
  const task::EnvConfig c;
  task::MultiTaskEnv env(c);
  env.reset(spec(8, 3, 0.08, 6));
  const sim::SceneLayout& s = env.world().layout();
  std::vector<float> near(c.robot.depth_width * c.robot.depth_height), far(near.size());
  // Facing the stairs from close up and from far: the riser is nearer in the first.
  const double close[3] = {-0.3, 0, c.robot.camera_height};
  const double away[3] = {-1.5, 0, c.robot.camera_height};
  env.world().render_depth_at(close, 0.0, 0.0, near.data());
  env.world().render_depth_at(away, 0.0, 0.0, far.data());
  const int mid = (c.robot.depth_height / 2) * c.robot.depth_width + c.robot.depth_width / 2;
  EXPECT_LT(near[mid], far[mid]);
  EXPECT_EQ(sim::scene_label(c.scene, s, close[0], close[1]), sim::kLabelStairs);
}

TEST(Env, LabelledViewsForTheSceneClassifier) {
  const task::EnvConfig c;
  task::MultiTaskEnv env(c);
  env.reset(spec(12, 2, 0.06, 6));
  const sim::SceneLayout& s = env.world().layout();
  std::vector<float> img(c.robot.depth_width * c.robot.depth_height);
  EXPECT_EQ(env.world().render_view_from(-0.8, 0.0, 0.0, img.data()), sim::kLabelStairs);
  EXPECT_EQ(env.world().render_view_from(s.platform_x + 1.0, 0.0, 0.0, img.data()), sim::kLabelObstacles);
  EXPECT_EQ(env.world().render_view_from(s.target_x - 0.5, s.target_y, 0.0, img.data()), sim::kLabelTarget);
  // Standing on the flat area the camera is raised by the stairs' height: compare to the ground view.
  std::vector<float> ground(img.size());
  env.world().render_view_from(-0.8, 0.0, 0.0, ground.data());
  EXPECT_NE(img, ground);
}

// clearance(): per column, the nearest depth among the rows that look above the
// horizon. At the start (camera 0.11 m up, 0.5 m before the first riser) with
// 0.08 m steps, riser 2 (top 0.16 m, 0.9 m ahead) rises into those rows; with
// 0.04 m steps and no obstacles nothing does (the floor and the low risers stay
// below the horizon), so every column reads 1 = nothing within range.
TEST(Env, ClearanceSeesWhatRisesAboveTheCameraStraightAhead) {
  const task::EnvConfig c;
  task::MultiTaskEnv env(c);
  const int w = c.robot.depth_width;
  env.reset(spec(3, 4, 0.08, 0));
  EXPECT_NEAR(env.clearance()[w / 2] * c.robot.depth_max_range, 0.9, 0.06);
  env.reset(spec(3, 4, 0.04, 0));
  for (int j = 0; j < w; ++j) EXPECT_FLOAT_EQ(env.clearance()[j], 1.0f) << "column " << j;
  // The floor is in the image, just not in the clearance row.
  float nearest = 1.0f;
  for (int i = 0; i < c.robot.depth_height; ++i) nearest = std::min(nearest, env.depth()[i * w + w / 2]);
  EXPECT_LT(nearest, 0.1f);
}

// With scan_columns > 0 the clearance row is the obstacle scan: level rays,
// uniform in angle, radial distance. Riser 2 of 0.08 m steps stands 0.9 m ahead
// across the stairs' 2 m width, so the ray at yaw phi meets it at 0.9 / cos(phi)
// up to |phi| = 0.84 rad: also at +-0.69 rad, outside the depth camera's +-0.6.
TEST(Env, ObstacleScanSeesRisersOutsideTheCameraView) {
  task::EnvConfig c;
  c.robot.scan_columns = 24;
  c.robot.scan_fov_x = 3.0;
  task::MultiTaskEnv env(c);
  ASSERT_EQ(env.clearance_width(), 24);
  env.reset(spec(3, 4, 0.08, 0));
  int checked = 0;
  for (int j = 0; j < 24; ++j) {
    const double yaw = 1.5 - 3.0 * (j + 0.5) / 24;
    if (std::abs(yaw) > 0.75) continue;
    EXPECT_NEAR(env.clearance()[j] * c.robot.depth_max_range, 0.9 / std::cos(yaw), 0.08 / std::cos(yaw))
        << "column " << j << ", yaw " << yaw;
    ++checked;
  }
  EXPECT_EQ(checked, 12);
  // 0.04 m steps: risers 1 and 2 (tops 0.04, 0.08 m) are below the camera, the
  // level rays pass over them to riser 3 (top 0.12 m), 1.3 m ahead.
  env.reset(spec(3, 4, 0.04, 0));
  for (int j = 7; j < 17; ++j) {  // |yaw| < 0.6: riser 3 is 1 m wide on each side
    const double yaw = 1.5 - 3.0 * (j + 0.5) / 24;
    EXPECT_NEAR(env.clearance()[j] * c.robot.depth_max_range, 1.3 / std::cos(yaw), 0.08 / std::cos(yaw))
        << "column " << j;
  }
}
