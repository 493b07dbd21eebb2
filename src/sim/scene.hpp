// The multi-task scene drawn from a seed: three steps of one height, the 6 x 6 m
// flat area with K obstacles placed with a guaranteed free path, the target.
// Scene frame: x towards the target, y left, z up; the first riser is at x = 0.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/enum_names.hpp"
#include "sim/params.hpp"

namespace comorph::sim {

enum class Variant { standard, mixed };  // mixed: some obstacles on the stair treads
constexpr auto enum_names(Variant) {
  return std::array{EnumName{Variant::standard, "standard"}, EnumName{Variant::mixed, "mixed"}};
}
Variant parse_variant(const std::string& name);  // throws std::invalid_argument listing the names

struct Box {          // axis-aligned box
  double x, y, z;     // m, centre
  double hx, hy, hz;  // m, half sizes
};

struct SceneLayout {
  double stair_height = 0.04;      // m, one height for the whole episode
  std::vector<Box> steps;          // steps.size() == SceneParams::steps; the last is the flat area
  std::vector<Box> obstacles;      // K boxes (mixed: the first ones are on the treads)
  double platform_x = 0;           // m, near edge of the flat area (top of the stairs)
  double platform_z = 0;           // m, height of the flat area (steps x stair_height)
  double area_end_x = 0;           // m, far edge of the flat area
  double target_x = 0, target_y = 0;  // m, target centre (on the flat area)
  double start_x = 0, start_y = 0, start_yaw = 0;  // m, m, rad: module 1's front face centre
  std::uint64_t seed = 0;
  Variant variant = Variant::standard;
};

// Draws the scene. stair_height <= 0 draws it from {a, b, c}; obstacles < 0
// takes params.obstacles. Throws std::invalid_argument for a K above
// params.max_obstacles or a scene where no free path can be found.
SceneLayout generate_scene(const SceneParams& params, std::uint64_t seed, double stair_height = 0,
                           int obstacles = -1, Variant variant = Variant::standard);

// True when a disc of radius params.path_clearance can travel from the start
// to the target without touching an obstacle or leaving the stairs/flat area
// (4-connected search on a 5 cm grid).
bool free_path_exists(const SceneParams& params, const SceneLayout& layout);

// Ground-truth scene class of a position of module 1 (what its camera faces):
// 0 = stairs (before or on the stairs), 1 = flat obstacle field, 2 = target zone.
enum SceneLabel : int { kLabelStairs = 0, kLabelObstacles = 1, kLabelTarget = 2 };
int scene_label(const SceneParams& params, const SceneLayout& layout, double head_x, double head_y);

// Floor height (m) under a point: a step, the flat area, or the ground (0).
double floor_height(const SceneLayout& layout, double x, double y);

}  // namespace comorph::sim
