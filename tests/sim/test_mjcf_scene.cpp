// MJCF generation, the model cache and seeded scenes.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "sim/mjcf.hpp"
#include "sim/model.hpp"
#include "sim/scene.hpp"
#include "support/test_support.hpp"

using namespace comorph::sim;
using comorph::Configuration;
using comorph::make_chain;
using comorph::test_support::read_text;

namespace {

// Module 2's back face docked to module 3's back face: valid plates, not a chain.
Configuration back_to_back_chain() {
  Configuration c = make_chain(3);
  c.C_s[1] = {2, 3, comorph::kBackFace, comorph::kBackFace, 1};
  return c;
}

}  // namespace

// tests/sim/fixtures/chain_<n>.xml were written by the count-based generator
// this one replaced, from configs/sim and scene seed 3 with 8 mixed obstacles:
// the MJCF, and so every run's physics, stays byte for byte the same.
TEST(Mjcf, ChainIsByteIdenticalToTheCountBasedGenerator) {
  const std::string source = COMORPH_SOURCE_DIR;
  const RobotParams rp = load_robot_params(source + "/configs/sim/robot.yaml");
  const SceneParams sp = load_scene_params(source + "/configs/sim/scene.yaml");
  const SceneLayout layout = generate_scene(sp, 3, 0, 8, Variant::mixed);
  for (int n = comorph::kMinModules; n <= comorph::kMaxModules; ++n) {
    const std::string fixture = read_text(source + "/tests/sim/fixtures/chain_" + std::to_string(n) + ".xml");
    ASSERT_FALSE(fixture.empty()) << n;
    EXPECT_EQ(build_mjcf(make_chain(n), rp, sp, layout), fixture) << n << " modules";
  }
}

TEST(Mjcf, RefusesAConfigurationMorphologyRejects) {
  const SceneParams sp;
  try {
    build_mjcf(back_to_back_chain(), RobotParams{}, sp, generate_scene(sp, 1));
    FAIL() << "built a configuration that is not a chain";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("the simulator cannot build this configuration"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("not a chain link"), std::string::npos) << e.what();
  }
}

TEST(Mjcf, CompilesForEveryChainLengthWithTheRightCounts) {
  const RobotParams rp;
  const SceneParams sp;
  const SceneLayout layout = generate_scene(sp, 7, 0.06, 6);
  for (int n = 2; n <= 10; ++n) {
    const ModelPtr m = compile_mjcf(build_mjcf(make_chain(n), rp, sp, layout));
    // world + per module (body, 2 wheels, back-plate link) + module 1's free front plate
    EXPECT_EQ(m->nbody, 1 + 4 * n + 1) << n;
    EXPECT_EQ(m->njnt, 1 + 4 * n) << n;
    EXPECT_EQ(m->nq, 7 + 4 * n) << n;
    EXPECT_EQ(m->nv, 6 + 4 * n) << n;
    EXPECT_EQ(m->nu, 4 * n) << n;
    EXPECT_EQ(m->jnt_type[0], mjJNT_FREE);
    // Actuator order: wheel_l, wheel_r, front, back per module.
    for (int k = 0; k < n; ++k) {
      const std::string id = std::to_string(k + 1);
      EXPECT_EQ(mj_name2id(m.get(), mjOBJ_ACTUATOR, ("wheel_l" + id).c_str()), 4 * k + kWheelLeft);
      EXPECT_EQ(mj_name2id(m.get(), mjOBJ_ACTUATOR, ("wheel_r" + id).c_str()), 4 * k + kWheelRight);
      EXPECT_EQ(mj_name2id(m.get(), mjOBJ_ACTUATOR, ("front" + id).c_str()), 4 * k + kFrontHinge);
      EXPECT_EQ(mj_name2id(m.get(), mjOBJ_ACTUATOR, ("back" + id).c_str()), 4 * k + kBackHinge);
    }
    // Total mass: modules + two wheels + two plates each.
    double mass = 0;
    for (int b = 1; b < m->nbody; ++b) mass += m->body_mass[b];
    EXPECT_NEAR(mass, n * (rp.body_mass + 2 * rp.wheel_mass + 2 * rp.plate_mass), 1e-9);
  }
}

TEST(Mjcf, StateOfAShorterChainIsAPrefixOfTheLongerOne) {
  const RobotParams rp;
  const SceneParams sp;
  const SceneLayout layout = generate_scene(sp, 1);
  const ModelPtr big = compile_mjcf(build_mjcf(make_chain(7), rp, sp, layout));
  const ModelPtr small = compile_mjcf(build_mjcf(make_chain(3), rp, sp, layout));
  for (int j = 0; j < small->njnt; ++j) {
    const char* name = mj_id2name(small.get(), mjOBJ_JOINT, j);
    const int jb = mj_name2id(big.get(), mjOBJ_JOINT, name);
    ASSERT_GE(jb, 0) << name;
    EXPECT_EQ(small->jnt_qposadr[j], big->jnt_qposadr[jb]) << name;
    EXPECT_EQ(small->jnt_dofadr[j], big->jnt_dofadr[jb]) << name;
  }
}

TEST(ModelCache, AppliedLayoutEqualsTheExportedScene) {
  const RobotParams rp;
  const SceneParams sp;
  ModelCache cache(rp, sp);
  for (std::uint64_t seed : {3u, 11u}) {
    const SceneLayout layout = generate_scene(sp, seed, 0, 8, Variant::mixed);
    ModelPtr cached(mj_copyModel(nullptr, cache.get(make_chain(5))));
    apply_layout(cached.get(), sp, layout);
    const ModelPtr exported = compile_mjcf(build_mjcf(make_chain(5), rp, sp, layout));
    ASSERT_EQ(cached->ngeom, exported->ngeom);
    for (int g = 0; g < cached->ngeom; ++g) {
      if (cached->geom_bodyid[g] != 0) continue;  // robot geoms: start pose differs, not the scene
      for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(cached->geom_pos[3 * g + a], exported->geom_pos[3 * g + a], 1e-6) << g;
        EXPECT_NEAR(cached->geom_size[3 * g + a], exported->geom_size[3 * g + a], 1e-6) << g;
      }
      EXPECT_EQ(cached->geom_contype[g], exported->geom_contype[g]) << g;
      EXPECT_EQ(cached->geom_group[g], exported->geom_group[g]) << g;
    }
  }
  EXPECT_EQ(cache.compilations(), 1);  // the second seed reused the compiled model
}

TEST(ModelCache, KeyedByConfigurationAndBuildsWhatItDescribes) {
  const RobotParams rp;
  const SceneParams sp;
  ModelCache cache(rp, sp);
  const mjModel* four = cache.get(make_chain(4));
  EXPECT_EQ(cache.get(make_chain(4)), four);
  const mjModel* five = cache.get(make_chain(5));
  EXPECT_NE(five, four);
  EXPECT_EQ(cache.compilations(), 2);
  EXPECT_EQ(model_fault(four, make_chain(4)), "");
  EXPECT_EQ(model_fault(five, make_chain(5)), "");
  EXPECT_NE(model_fault(four, make_chain(5)).find("16 actuators for 5 modules"), std::string::npos);
  EXPECT_NE(model_fault(four, back_to_back_chain()).find("not a chain link"), std::string::npos);
  EXPECT_THROW(cache.get(back_to_back_chain()), std::invalid_argument);
  EXPECT_EQ(cache.compilations(), 2);
}

TEST(Scene, SameSeedSameSceneDifferentSeedDifferentScene) {
  const SceneParams sp;
  const SceneLayout a = generate_scene(sp, 42), b = generate_scene(sp, 42), c = generate_scene(sp, 43);
  ASSERT_EQ(a.obstacles.size(), b.obstacles.size());
  EXPECT_EQ(a.stair_height, b.stair_height);
  EXPECT_EQ(a.target_y, b.target_y);
  EXPECT_EQ(a.start_yaw, b.start_yaw);
  for (std::size_t i = 0; i < a.obstacles.size(); ++i) {
    EXPECT_EQ(a.obstacles[i].x, b.obstacles[i].x);
    EXPECT_EQ(a.obstacles[i].y, b.obstacles[i].y);
  }
  EXPECT_NE(a.obstacles[0].x, c.obstacles[0].x);
}

TEST(Scene, GeometryFollowsTheParameters) {
  const SceneParams sp;
  std::set<double> heights;
  for (std::uint64_t seed = 0; seed < 60; ++seed) {
    const SceneLayout s = generate_scene(sp, seed);
    heights.insert(s.stair_height);
    ASSERT_EQ(int(s.steps.size()), sp.steps);
    EXPECT_NEAR(s.platform_z, 3 * s.stair_height, 1e-12);
    EXPECT_NEAR(floor_height(s, 0.2, 0), s.stair_height, 1e-12);       // first tread
    EXPECT_NEAR(floor_height(s, 0.6, 0), 2 * s.stair_height, 1e-12);   // second tread
    EXPECT_NEAR(floor_height(s, 3.0, 2.5), 3 * s.stair_height, 1e-12); // flat area, off the lane
    EXPECT_NEAR(floor_height(s, 0.2, 1.5), 0.0, 1e-12);                // beside the stairs: ground
    EXPECT_EQ(int(s.obstacles.size()), sp.obstacles);
    for (const Box& o : s.obstacles) {
      EXPECT_GE(o.x - o.hx, s.platform_x + sp.obstacle_region_start - 1e-9);
      EXPECT_LE(o.x + o.hx, s.platform_x + sp.obstacle_region_start + sp.obstacle_region_length + 1e-9);
      EXPECT_LE(std::abs(o.y) + o.hy, 0.5 * sp.area_width + 1e-9);
      EXPECT_NEAR(2 * o.hz, sp.obstacle_height, 1e-12);
    }
    EXPECT_LE(std::abs(s.target_y), sp.target_lateral);
  }
  EXPECT_EQ(heights, (std::set<double>{sp.stair_height_a, sp.stair_height_b, sp.stair_height_c}));
}

TEST(Scene, FreePathIsGuaranteedOverManySeeds) {
  const SceneParams sp;
  for (Variant v : {Variant::standard, Variant::mixed})
    for (int k : {6, 8, 10})
      for (std::uint64_t seed = 0; seed < 150; ++seed) {
        const SceneLayout s = generate_scene(sp, seed, 0, k, v);
        ASSERT_TRUE(free_path_exists(sp, s)) << "seed " << seed << " K " << k;
        if (v == Variant::mixed) {
          int on_stairs = 0;
          for (const Box& o : s.obstacles) on_stairs += o.x < s.platform_x;
          EXPECT_EQ(on_stairs, sp.mixed_on_stairs);
        }
      }
}

TEST(Scene, PathCheckDetectsABlockedField) {
  const SceneParams sp;
  SceneLayout s = generate_scene(sp, 5, 0, 0);
  ASSERT_TRUE(free_path_exists(sp, s));
  // A wall of obstacles across the whole flat area.
  for (double y = -3.0; y <= 3.0; y += 0.3)
    s.obstacles.push_back({s.platform_x + 2.0, y, s.platform_z + 0.2, 0.15, 0.15, 0.2});
  EXPECT_FALSE(free_path_exists(sp, s));
}

TEST(Scene, LabelsFollowTheRobotThroughTheScenario) {
  const SceneParams sp;
  const SceneLayout s = generate_scene(sp, 9);
  EXPECT_EQ(scene_label(sp, s, s.start_x, 0), kLabelStairs);
  EXPECT_EQ(scene_label(sp, s, 0.3, 0), kLabelStairs);
  EXPECT_EQ(scene_label(sp, s, s.platform_x + 1.5, 0), kLabelObstacles);
  EXPECT_EQ(scene_label(sp, s, s.target_x - 1.0, s.target_y), kLabelTarget);
}

TEST(Scene, RejectsTooManyObstaclesAndUnknownVariants) {
  const SceneParams sp;
  EXPECT_THROW(generate_scene(sp, 1, 0, sp.max_obstacles + 1), std::invalid_argument);
  EXPECT_THROW(parse_variant("spiral"), std::invalid_argument);
  EXPECT_EQ(parse_variant("mixed"), Variant::mixed);
}
