// World: sensors against known geometry, energy accounting, contacts,
// reconfiguration state transfer, instability detection.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "sim/mjcf.hpp"
#include "sim/world.hpp"

using namespace comorph::sim;
using comorph::make_chain;

namespace {

SceneParams quiet_scene() {
  SceneParams sp;
  sp.start_lateral_noise = 0;
  sp.start_yaw_noise = 0;
  return sp;
}

// Empty scene (no obstacles) with the robot at x = start_x, y = 0, heading +x.
SceneLayout empty_layout(const SceneParams& sp, double stair_height = 0.04) {
  return generate_scene(sp, 1, stair_height, 0);
}

std::vector<double> ctrl_all(int modules, double wheel, double hinge) {
  std::vector<double> c(4 * modules, 0.0);
  for (int k = 0; k < modules; ++k) {
    c[4 * k + kWheelLeft] = wheel;
    c[4 * k + kWheelRight] = wheel;
    c[4 * k + kFrontHinge] = k > 0 ? hinge : 0.0;
  }
  return c;
}

}  // namespace

TEST(Sensors, DistanceToAKnownObstacle) {
  const RobotParams rp;
  const SceneParams sp = quiet_scene();
  SceneLayout s = empty_layout(sp);
  const double x1 = s.start_x - 0.5 * rp.module_length;  // module 1's centre
  s.obstacles.push_back({x1, 0.60, 0.2, 0.15, 0.15, 0.2});  // left face at y = 0.45
  World w(rp, sp);
  w.reset(s, make_chain(4));
  std::vector<float> d(8);
  w.read_distances(d.data());
  EXPECT_NEAR(d[0] * rp.distance_range, 0.45, 1e-4);  // module 1 left
  EXPECT_FLOAT_EQ(d[1], 1.0f);                        // module 1 right: nothing within range
  EXPECT_FLOAT_EQ(d[4], 1.0f);                        // module 3 left: behind the obstacle
  EXPECT_FLOAT_EQ(d[5], 1.0f);
}

TEST(Sensors, DepthOfAKnownWall) {
  RobotParams rp;
  rp.depth_pitch = 0.0;  // optical axis horizontal: a wall across x has one planar depth
  const SceneParams sp = quiet_scene();
  SceneLayout s = empty_layout(sp);
  const double wall_distance = 0.6;  // m from the camera (module 1's front face)
  s.obstacles.push_back({s.start_x + wall_distance + 0.05, 0, 0.5, 0.05, 1.0, 0.5});
  World w(rp, sp);
  w.reset(s, make_chain(3));
  std::vector<float> depth(rp.depth_width * rp.depth_height);
  w.render_depth(depth.data());
  const int h = rp.depth_height, wd = rp.depth_width;
  for (int i = h / 2 - 2; i < h / 2 + 2; ++i)
    for (int j = wd / 2 - 2; j < wd / 2 + 2; ++j)
      EXPECT_NEAR(depth[i * wd + j], wall_distance / rp.depth_max_range, 1e-5) << i << "," << j;
  for (float v : depth) {
    EXPECT_GE(v, 0.01f);
    EXPECT_LE(v, 1.0f);
  }
  // Bottom row sees the floor closer than the wall.
  EXPECT_LT(depth[(h - 1) * wd + wd / 2], wall_distance / rp.depth_max_range);
}

TEST(Sensors, DepthRaysAgreeWithMujocoRayOnSceneGeoms) {
  const RobotParams rp;
  const SceneParams sp;
  for (std::uint64_t seed : {2u, 5u}) {
    World w(rp, sp);
    SceneLayout s = generate_scene(sp, seed, 0.08, 8, Variant::mixed);
    w.reset(s, make_chain(5));
    // Stand module 1 on the flat area facing the obstacles to see them.
    mjData* d = w.mutable_data();
    d->qpos[0] = s.platform_x + 0.8;
    d->qpos[2] = s.platform_z + rp.wheel_radius + 0.01;
    mj_forward(w.model(), d);
    const mjtByte scene_only[mjNGROUP] = {1, 0, 0, 0, 0, 0};
    int hits = 0;
    for (int px = 0; px < rp.depth_width * rp.depth_height; ++px) {
      double p[3], v[3];
      w.depth_ray(px, p, v);
      int geom = -1;
      const double ref = mj_ray(w.model(), w.data(), p, v, scene_only, 1, -1, &geom);
      const double range = 10.0;  // m; mj_ray's plane is finite (20 m), ours is not
      const double ours = w.cast_ray(p, v, range);
      if (ref < 0 || ref > range) {
        EXPECT_LT(ours, 0) << px;
      } else {
        EXPECT_NEAR(ours, ref, 1e-6) << "pixel " << px << " geom " << geom;
        ++hits;
      }
    }
    EXPECT_GT(hits, 0);
  }
}

TEST(Sensors, DepthFromAnArbitraryPoseMatchesTheCamera) {
  const RobotParams rp;
  const SceneParams sp = quiet_scene();
  World w(rp, sp);
  w.reset(generate_scene(sp, 4), make_chain(2));
  const int n = rp.depth_width * rp.depth_height;
  std::vector<float> cam(n), posed(n);
  w.render_depth(cam.data());
  double p[3], v[3];
  w.depth_ray(0, p, v);
  w.render_depth_at(p, w.heading(), 0.0, posed.data());
  for (int i = 0; i < n; ++i) EXPECT_NEAR(cam[i], posed[i], 2e-3) << i;  // start pose is level to ~1e-4 rad
}

TEST(Energy, IdleDrawOverAKnownTime) {
  const RobotParams rp;
  const SceneParams sp = quiet_scene();
  World w(rp, sp);
  const int n = 4;
  w.reset(empty_layout(sp), make_chain(n));
  const std::vector<double> hold = ctrl_all(n, 0.0, 0.0);
  for (int i = 0; i < 30; ++i) w.step_control(hold.data());  // let it settle
  const double e0 = w.energy_used();
  const int steps = 62;  // 1.984 s
  for (int i = 0; i < steps; ++i) w.step_control(hold.data());
  const double t = steps * rp.control_period;
  const double idle = n * rp.idle_power * t;
  EXPECT_GE(w.energy_used() - e0, idle * (1 - 1e-9));
  EXPECT_LE(w.energy_used() - e0, idle * 1.02);  // holding still costs little beyond idle
  for (int k = 0; k < n; ++k) EXPECT_NEAR(w.battery_fraction(k), 1.0 - w.module_energy()[k] / rp.battery_capacity, 1e-12);
}

TEST(Energy, DrivingCostsMoreThanIdling) {
  const RobotParams rp;
  const SceneParams sp = quiet_scene();
  World w(rp, sp);
  w.reset(empty_layout(sp), make_chain(3));
  const std::vector<double> drive = ctrl_all(3, 5.0, 0.0);
  double e = 0;
  for (int i = 0; i < 40; ++i) e += w.step_control(drive.data()).energy_J;
  EXPECT_NEAR(e, w.energy_used(), 1e-9);
  EXPECT_GT(e, 3 * rp.idle_power * 40 * rp.control_period * 1.005);
}

TEST(Contacts, DrivingIntoAnObstacleIsDetected) {
  const RobotParams rp;
  const SceneParams sp = quiet_scene();
  SceneLayout s = empty_layout(sp);
  World free_world(rp, sp), blocked_world(rp, sp);
  free_world.reset(s, make_chain(3));
  s.obstacles.push_back({s.start_x + 0.25, 0, 0.2, 0.15, 0.15, 0.2});  // just ahead, on the ground
  blocked_world.reset(s, make_chain(3));
  const std::vector<double> drive = ctrl_all(3, 5.0, 0.0);
  bool hit_free = false, hit_blocked = false;
  for (int i = 0; i < 60; ++i) {
    hit_free = hit_free || free_world.step_control(drive.data()).obstacle_contact;
    hit_blocked = hit_blocked || blocked_world.step_control(drive.data()).obstacle_contact;
  }
  EXPECT_FALSE(hit_free);
  EXPECT_TRUE(hit_blocked);
}

TEST(Reconfiguration, KeptModulesCarryTheirStateExactly) {
  const RobotParams rp;
  const SceneParams sp;
  World w(rp, sp);
  w.reset(generate_scene(sp, 3, 0.06, 0), make_chain(6));
  std::vector<double> ctrl = ctrl_all(6, 4.0, 0.0);
  for (int i = 0; i < 50; ++i) {
    for (int k = 1; k < 6; ++k) ctrl[4 * k + kFrontHinge] = 0.3 * std::sin(0.2 * i + k);
    w.step_control(ctrl.data());
  }
  const std::vector<double> qpos(w.data()->qpos, w.data()->qpos + w.model()->nq);
  const std::vector<double> qvel(w.data()->qvel, w.data()->qvel + w.model()->nv);
  std::vector<double> xpos, energy;
  for (int k = 0; k < 3; ++k) {
    xpos.insert(xpos.end(), w.module_pos(k), w.module_pos(k) + 3);
    energy.push_back(w.module_energy()[k]);
  }
  const double time = w.time(), used = w.energy_used();
  const int compilations = w.compilations();

  w.reconfigure(make_chain(3));
  EXPECT_EQ(w.modules(), 3);
  EXPECT_EQ(w.configuration(), make_chain(3));
  EXPECT_EQ(w.model()->nq, 7 + 4 * 3);
  for (int i = 0; i < w.model()->nq; ++i) EXPECT_EQ(w.data()->qpos[i], qpos[i]) << i;
  for (int i = 0; i < w.model()->nv; ++i) EXPECT_EQ(w.data()->qvel[i], qvel[i]) << i;
  for (int k = 0; k < 3; ++k) {
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(w.module_pos(k)[a], xpos[3 * k + a], 1e-12);
    EXPECT_EQ(w.module_energy()[k], energy[k]);
  }
  EXPECT_EQ(w.time(), time);
  EXPECT_DOUBLE_EQ(w.energy_used(), used);  // shed modules' energy still counts
  EXPECT_EQ(w.compilations(), compilations + 1);  // the 3-chain model compiled once...
  w.reset(generate_scene(sp, 4, 0.04, 0), make_chain(6));
  w.reconfigure(make_chain(3));
  EXPECT_EQ(w.compilations(), compilations + 1);  // ...and reused afterwards
  EXPECT_THROW(w.reconfigure(make_chain(5)), std::invalid_argument);  // only fewer modules
  EXPECT_THROW(w.reconfigure(make_chain(3)), std::invalid_argument);  // sheds none
  EXPECT_EQ(w.configuration(), make_chain(3));  // a refused reconfiguration changes nothing
}

TEST(Stability, NanStateIsReportedNotHidden) {
  const RobotParams rp;
  const SceneParams sp = quiet_scene();
  World w(rp, sp);
  w.reset(empty_layout(sp), make_chain(2));
  const std::vector<double> hold = ctrl_all(2, 0.0, 0.0);
  EXPECT_EQ(w.step_control(hold.data()).instability, Instability::none);
  w.mutable_data()->qvel[0] = std::nan("");
  EXPECT_NE(w.step_control(hold.data()).instability, Instability::none);
}

// The configuration model decides at the start, 0.5 m before the first riser.
// Rows (of the centre column) whose depth changes between 0.04 m and 0.08 m
// stairs: the decision camera must show the height as several rows, the wide
// motion camera shows it as about one per riser.
int rows_that_see_the_height(const RobotParams& rp, bool decision) {
  const SceneParams sp = quiet_scene();
  const int w = decision ? rp.decision_depth_width : rp.depth_width;
  const int h = decision ? rp.decision_depth_height : rp.depth_height;
  std::vector<float> low(std::size_t(w) * h), high(low.size());
  World world(rp, sp);
  for (auto [height, out] : {std::pair{0.04, &low}, std::pair{0.08, &high}}) {
    world.reset(empty_layout(sp, height), make_chain(4));
    if (decision)
      world.render_decision_depth(out->data());
    else
      world.render_depth(out->data());
  }
  int rows = 0;
  for (int i = 0; i < h; ++i) rows += std::abs(low[std::size_t(i) * w + w / 2] - high[std::size_t(i) * w + w / 2]) > 0.01f;
  return rows;
}

TEST(Sensors, DecisionCameraShowsTheStairHeightAsSeveralRows) {
  const RobotParams rp;
  const int decision_rows = rows_that_see_the_height(rp, true);
  const int motion_rows = rows_that_see_the_height(rp, false);
  std::printf("rows that differ between 0.04 and 0.08 m stairs: decision camera %d of %d, motion camera %d of %d\n",
              decision_rows, rp.decision_depth_height, motion_rows, rp.depth_height);
  EXPECT_GE(decision_rows, 8);
  EXPECT_GE(decision_rows, 2 * motion_rows);
}
