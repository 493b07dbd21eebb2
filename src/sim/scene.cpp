#include "sim/scene.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <random>
#include <stdexcept>

namespace comorph::sim {

Variant parse_variant(const std::string& name) {
  Variant v{};
  if (!enum_from_name(name, v))
    throw std::invalid_argument("unknown scenario variant '" + name + "' (" + enum_name_list<Variant>(", ") + ")");
  return v;
}

namespace {

// Uniform double in [lo, hi] from the raw engine output, so that the scene does
// not depend on the standard library's distribution implementation.
double uniform(std::mt19937_64& rng, double lo, double hi) {
  const double u = double(rng() >> 11) * (1.0 / 9007199254740992.0);
  return lo + (hi - lo) * u;
}

bool overlaps(const Box& a, const Box& b, double gap) {
  return std::abs(a.x - b.x) < a.hx + b.hx + gap && std::abs(a.y - b.y) < a.hy + b.hy + gap;
}

}  // namespace

double floor_height(const SceneLayout& layout, double x, double y) {
  double z = 0;
  for (const Box& s : layout.steps)
    if (std::abs(x - s.x) <= s.hx && std::abs(y - s.y) <= s.hy) z = std::max(z, s.z + s.hz);
  return z;
}

SceneLayout generate_scene(const SceneParams& p, std::uint64_t seed, double stair_height,
                           int obstacles, Variant variant) {
  if (obstacles < 0) obstacles = p.obstacles;
  if (obstacles > p.max_obstacles)
    throw std::invalid_argument("obstacles " + std::to_string(obstacles) + " exceeds max_obstacles " +
                                std::to_string(p.max_obstacles));
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + 12345);
  SceneLayout s;
  s.seed = seed;
  s.variant = variant;
  const double heights[3] = {p.stair_height_a, p.stair_height_b, p.stair_height_c};
  const double drawn = heights[rng() % 3];
  s.stair_height = stair_height > 0 ? stair_height : drawn;

  // Steps 1..steps-1 are treads; the last step is the flat area itself.
  const double h = s.stair_height;
  s.platform_x = (p.steps - 1) * p.tread;
  s.platform_z = p.steps * h;
  s.area_end_x = s.platform_x + p.area_length;
  for (int k = 1; k < p.steps; ++k)
    s.steps.push_back({(k - 0.5) * p.tread, 0, 0.5 * k * h, 0.5 * p.tread, 0.5 * p.stair_width,
                       0.5 * k * h});
  s.steps.push_back({s.platform_x + 0.5 * p.area_length, 0, 0.5 * s.platform_z,
                     0.5 * p.area_length, 0.5 * p.area_width, 0.5 * s.platform_z});

  s.start_x = -p.start_gap;
  s.start_y = uniform(rng, -p.start_lateral_noise, p.start_lateral_noise);
  s.start_yaw = uniform(rng, -p.start_yaw_noise, p.start_yaw_noise);
  s.target_x = s.area_end_x - p.target_margin;
  s.target_y = uniform(rng, -p.target_lateral, p.target_lateral);

  const double half = 0.5 * p.obstacle_size;
  const int on_stairs = variant == Variant::mixed ? std::min(obstacles, p.mixed_on_stairs) : 0;
  for (int attempt = 0; attempt < 2000; ++attempt) {
    s.obstacles.clear();
    int guard = 0;
    while (int(s.obstacles.size()) < obstacles && guard++ < 10000) {
      Box b{0, 0, 0, half, half, 0.5 * p.obstacle_height};
      if (int(s.obstacles.size()) < on_stairs && p.steps > 1) {
        const int k = 1 + int(rng() % std::uint64_t(p.steps - 1));  // tread k, height k*h
        b.x = (k - 0.5) * p.tread;
        b.y = uniform(rng, -0.5 * p.stair_width + half, 0.5 * p.stair_width - half);
        b.z = k * h + b.hz;
      } else {
        const double x0 = s.platform_x + p.obstacle_region_start + half;
        const double x1 = s.platform_x + p.obstacle_region_start + p.obstacle_region_length - half;
        b.x = uniform(rng, x0, x1);
        b.y = uniform(rng, -0.5 * p.area_width + half, 0.5 * p.area_width - half);
        b.z = s.platform_z + b.hz;
        if (std::hypot(b.x - s.target_x, b.y - s.target_y) < p.target_radius + half + 0.3) continue;
      }
      bool clash = false;
      for (const Box& o : s.obstacles) clash = clash || overlaps(b, o, 0.02);
      if (!clash) s.obstacles.push_back(b);
    }
    if (int(s.obstacles.size()) == obstacles && free_path_exists(p, s)) return s;
  }
  throw std::invalid_argument("no scene with a free path found for seed " + std::to_string(seed));
}

bool free_path_exists(const SceneParams& p, const SceneLayout& s) {
  const double cell = 0.05;
  const double x0 = s.start_x, x1 = s.area_end_x;
  const double y0 = -0.5 * p.area_width;
  const int nx = int(std::ceil((x1 - x0) / cell)) + 1;
  const int ny = int(std::ceil(p.area_width / cell)) + 1;
  const double c = p.path_clearance;
  auto free = [&](int i, int j) {
    const double x = x0 + i * cell, y = y0 + j * cell;
    // Before the flat area the robot must stay on the 2 m wide stair lane.
    const double half_width = x < s.platform_x ? 0.5 * p.stair_width : 0.5 * p.area_width;
    if (std::abs(y) > half_width - c) return false;
    for (const Box& o : s.obstacles)
      if (std::abs(x - o.x) < o.hx + c && std::abs(y - o.y) < o.hy + c) return false;
    return true;
  };
  auto index = [&](double x, double y) {
    return std::make_pair(int(std::lround((x - x0) / cell)), int(std::lround((y - y0) / cell)));
  };
  const auto [si, sj] = index(s.start_x, s.start_y);
  const auto [ti, tj] = index(s.target_x, s.target_y);
  if (!free(si, sj) || !free(ti, tj)) return false;
  std::vector<char> seen(std::size_t(nx) * ny, 0);
  std::deque<std::pair<int, int>> queue{{si, sj}};
  seen[std::size_t(si) * ny + sj] = 1;
  const int di[4] = {1, -1, 0, 0}, dj[4] = {0, 0, 1, -1};
  while (!queue.empty()) {
    const auto [i, j] = queue.front();
    queue.pop_front();
    if (i == ti && j == tj) return true;
    for (int k = 0; k < 4; ++k) {
      const int a = i + di[k], b = j + dj[k];
      if (a < 0 || b < 0 || a >= nx || b >= ny) continue;
      char& flag = seen[std::size_t(a) * ny + b];
      if (flag || !free(a, b)) continue;
      flag = 1;
      queue.emplace_back(a, b);
    }
  }
  return false;
}

int scene_label(const SceneParams& p, const SceneLayout& s, double head_x, double head_y) {
  if (std::hypot(head_x - s.target_x, head_y - s.target_y) < p.target_zone_distance)
    return kLabelTarget;
  if (head_x < s.platform_x + 0.3) return kLabelStairs;
  return kLabelObstacles;
}

}  // namespace comorph::sim
