#include "sim/world.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include "sim/mjcf.hpp"

namespace comorph::sim {

World::World(const RobotParams& robot, const SceneParams& scene, std::shared_ptr<ModelCache> cache)
    : robot_(robot), scene_(scene), cache_(std::move(cache)) {
  install_quiet_mujoco_warnings();
  if (!cache_) cache_ = std::make_shared<ModelCache>(robot_, scene_);
  substeps_ = int(std::lround(robot_.control_period / robot_.physics_timestep));
  rays_ = make_rays(robot_.depth_width, robot_.depth_height, robot_.depth_fov_x, robot_.depth_fov_y,
                    robot_.depth_pitch);
  decision_rays_ = make_rays(robot_.decision_depth_width, robot_.decision_depth_height, robot_.decision_fov_x,
                             robot_.decision_fov_y, robot_.decision_pitch);
  if (robot_.scan_columns > 0) scan_rays_ = make_fan(robot_.scan_columns, robot_.scan_fov_x);
}

World::RaySet World::make_fan(int columns, double fov_x) {
  RaySet r;
  r.dirs.resize(std::size_t(3) * columns);
  r.forward_dot.assign(std::size_t(columns), 1.0);  // radial distance
  for (int j = 0; j < columns; ++j) {
    const double yaw = 0.5 * fov_x - fov_x * (j + 0.5) / columns;  // + left
    r.dirs[3 * std::size_t(j)] = std::cos(yaw);
    r.dirs[3 * std::size_t(j) + 1] = std::sin(yaw);
    r.dirs[3 * std::size_t(j) + 2] = 0.0;
  }
  return r;
}

World::RaySet World::make_rays(int w, int h, double fov_x, double fov_y, double p) {
  // Pinhole grid, row 0 at the top, column 0 at the left.
  RaySet r;
  r.dirs.resize(std::size_t(3) * w * h);
  r.forward_dot.resize(std::size_t(w) * h);
  const double fwd[3] = {std::cos(p), 0, -std::sin(p)};
  const double up[3] = {std::sin(p), 0, std::cos(p)};
  const double left[3] = {0, 1, 0};
  const double tx = std::tan(0.5 * fov_x), ty = std::tan(0.5 * fov_y);
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j) {
      const double u = (1.0 - 2.0 * (j + 0.5) / w) * tx;  // + left
      const double v = (1.0 - 2.0 * (i + 0.5) / h) * ty;  // + up
      double d[3];
      for (int a = 0; a < 3; ++a) d[a] = fwd[a] + u * left[a] + v * up[a];
      const double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      const std::size_t px = std::size_t(i) * w + j;
      for (int a = 0; a < 3; ++a) r.dirs[3 * px + a] = d[a] / n;
      r.forward_dot[px] = 1.0 / n;
    }
  return r;
}

World::Body& World::body(const Configuration& config) {
  for (const auto& b : bodies_)
    if (b->configuration == config) return *b;
  auto b = std::make_unique<Body>();
  b->configuration = config;
  b->model.reset(mj_copyModel(nullptr, cache_->get(config)));  // throws for an invalid config
  b->modules = module_count(config);
  b->data.reset(mj_makeData(b->model.get()));
  for (int k = 0; k < b->modules; ++k) {
    const std::string name = "module" + std::to_string(k + 1);
    b->module_body[k] = mj_name2id(b->model.get(), mjOBJ_BODY, name.c_str());
  }
  bodies_.push_back(std::move(b));
  return *bodies_.back();
}

void World::bind(const Configuration& config) {
  Body& b = body(config);
  if (!b.layout_applied) {
    apply_layout(b.model.get(), scene_, layout_);
    b.layout_applied = true;
  }
  body_ = &b;
  modules_ = b.modules;
  model_ = b.model.get();
  data_ = b.data.get();
  module_body_ = b.module_body;
  first_obstacle_geom_ = mj_name2id(model_, mjOBJ_GEOM, "obstacle0");
  first_step_geom_ = mj_name2id(model_, mjOBJ_GEOM, "step1");
  target_geom_ = mj_name2id(model_, mjOBJ_GEOM, "target");
  floor_geom_ = mj_name2id(model_, mjOBJ_GEOM, "floor");
}

void World::reset(const SceneLayout& layout, const Configuration& config) {
  if (int(layout.steps.size()) != scene_.steps)
    throw std::invalid_argument("layout does not match SceneParams::steps");
  layout_ = layout;
  for (const auto& b : bodies_) b->layout_applied = false;
  bind(config);
  mj_resetData(model_, data_);
  // Module 1's axle centre half a module behind the start face, standing on its wheels.
  const double L = robot_.module_length, yaw = layout_.start_yaw;
  double* q = data_->qpos;
  q[0] = layout_.start_x - 0.5 * L * std::cos(yaw);
  q[1] = layout_.start_y - 0.5 * L * std::sin(yaw);
  q[2] = robot_.wheel_radius + 1e-4;
  q[3] = std::cos(0.5 * yaw);
  q[4] = 0;
  q[5] = 0;
  q[6] = std::sin(0.5 * yaw);
  mj_forward(model_, data_);
  energy_.fill(0.0);
  shed_energy_ = 0;
}

PhysicsStepInfo World::step_control(const double* ctrl) {
  PhysicsStepInfo info;
  std::memcpy(data_->ctrl, ctrl, sizeof(double) * model_->nu);
  const int first_obstacle = first_obstacle_geom_;
  const int last_obstacle = first_obstacle_geom_ + int(layout_.obstacles.size());
  const int first_step = first_step_geom_, last_step = first_step_geom_ + scene_.steps;
  const double dt = model_->opt.timestep;
  const double inv_eff = 1.0 / robot_.motor_efficiency;
  const int warn_qacc = data_->warning[mjWARN_BADQACC].number;
  const int warn_qpos = data_->warning[mjWARN_BADQPOS].number;
  const int warn_qvel = data_->warning[mjWARN_BADQVEL].number;
  for (int s = 0; s < substeps_; ++s) {
    mj_step(model_, data_);
    // MuJoCo resets the state itself on bad numbers and only counts a warning: catch it.
    if (data_->warning[mjWARN_BADQACC].number != warn_qacc) info.instability = Instability::bad_qacc;
    else if (data_->warning[mjWARN_BADQPOS].number != warn_qpos) info.instability = Instability::bad_qpos;
    else if (data_->warning[mjWARN_BADQVEL].number != warn_qvel) info.instability = Instability::bad_qvel;
    if (info.instability != Instability::none) break;
    // Energy: idle draw plus each motor's electrical power.
    for (int k = 0; k < modules_; ++k) {
      double p = robot_.idle_power;
      for (int a = kActuatorsPerModule * k; a < kActuatorsPerModule * (k + 1); ++a) {
        const double tau = data_->actuator_force[a];
        p += std::abs(tau * data_->actuator_velocity[a]) * inv_eff + robot_.copper_loss * tau * tau;
      }
      energy_[k] += p * dt;
      info.energy_J += p * dt;
    }
    for (int c = 0; c < data_->ncon; ++c) {
      const int g1 = data_->contact[c].geom1, g2 = data_->contact[c].geom2;
      if ((g1 >= first_obstacle && g1 < last_obstacle) || (g2 >= first_obstacle && g2 < last_obstacle))
        info.obstacle_contact = true;
      if ((g1 >= first_step && g1 < last_step) || (g2 >= first_step && g2 < last_step))
        info.stair_contact = true;
    }
  }
  // mj_step leaves xpos/xmat at the pre-integration state: refresh the kinematics so
  // that sensors and checks see the current qpos (cheap: no dynamics).
  mj_kinematics(model_, data_);
  if (info.instability == Instability::none) {
    for (int i = 0; i < model_->nq; ++i)
      if (!std::isfinite(data_->qpos[i])) info.instability = Instability::nan_state;
    for (int i = 0; i < model_->nv; ++i)
      if (!std::isfinite(data_->qvel[i])) info.instability = Instability::nan_state;
  }
  return info;
}

void World::reconfigure(const Configuration& part) {
  if (std::string fault = validate_sub_configuration(configuration(), part); !fault.empty())
    throw std::invalid_argument("reconfigure: " + fault);
  const mjData* old_d = data_;
  const int old_n = modules_;
  bind(part);
  mj_resetData(model_, data_);
  data_->time = old_d->time;
  // The kept modules' coordinates are a prefix of the longer chain's (mjcf.hpp):
  // a chain's sub-configurations keep modules 1..k.
  std::memcpy(data_->qpos, old_d->qpos, sizeof(double) * model_->nq);
  std::memcpy(data_->qvel, old_d->qvel, sizeof(double) * model_->nv);
  std::memcpy(data_->qacc_warmstart, old_d->qacc_warmstart, sizeof(double) * model_->nv);
  std::memcpy(data_->ctrl, old_d->ctrl, sizeof(double) * model_->nu);
  std::memcpy(data_->warning, old_d->warning, sizeof(data_->warning));
  for (int k = modules_; k < old_n; ++k) {
    shed_energy_ += energy_[k];
    energy_[k] = 0;
  }
  mj_forward(model_, data_);
}

double World::heading() const {
  const double* m = module_mat(0);
  return std::atan2(m[3], m[0]);
}

double World::energy_used() const {
  double e = shed_energy_;
  for (int k = 0; k < modules_; ++k) e += energy_[k];
  return e;
}

double World::battery_fraction(int k) const {
  return std::max(0.0, 1.0 - energy_[k] / robot_.battery_capacity);
}

// Scene geoms are axis-aligned boxes (steps, obstacles), the floor plane z = 0
// and the target post; a slab test per box is much cheaper than mj_ray's
// per-geom dispatch over the whole model (tests check both agree).
double World::ray_scene(const double p[3], const double v[3], double max_dist) const {
  double best = max_dist;
  bool hit = false;
  if (v[2] < 0) {  // floor
    const double t = -p[2] / v[2];
    if (t >= 0 && t < best) best = t, hit = true;
  }
  const int first = first_step_geom_, boxes_end = first_obstacle_geom_ + int(layout_.obstacles.size());
  for (int g = first; g < boxes_end; ++g) {
    if (g >= first_step_geom_ + scene_.steps && g < first_obstacle_geom_) continue;
    const double* c = data_->geom_xpos + 3 * g;
    const double* hs = model_->geom_size + 3 * g;
    double t0 = 0, t1 = best;
    bool miss = false;
    for (int a = 0; a < 3 && !miss; ++a) {
      const double lo = c[a] - hs[a] - p[a], hi = c[a] + hs[a] - p[a];
      if (std::abs(v[a]) < 1e-12) {
        if (lo > 0 || hi < 0) miss = true;
        continue;
      }
      double ta = lo / v[a], tb = hi / v[a];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
      if (t0 > t1) miss = true;
    }
    if (!miss && t0 < best) best = t0, hit = true;
  }
  {  // target post (cylinder): bounding-sphere reject, then MuJoCo's exact test
    const int g = target_geom_;
    const double* c = data_->geom_xpos + 3 * g;
    const double d[3] = {c[0] - p[0], c[1] - p[1], c[2] - p[2]};
    const double along = d[0] * v[0] + d[1] * v[1] + d[2] * v[2];
    const double r = model_->geom_rbound[g];
    const double perp2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - along * along;
    if (along > -r && along - r < best && perp2 < r * r) {
      const double t = mju_rayGeom(c, data_->geom_xmat + 9 * g, model_->geom_size + 3 * g, p, v, mjGEOM_CYLINDER);
      if (t >= 0 && t < best) best = t, hit = true;
    }
  }
  return hit ? best : -1.0;
}

double World::cast_ray(const double pnt[3], const double dir[3], double max_dist) const {
  return ray_scene(pnt, dir, max_dist);
}

void World::render_depth_at(const double pos[3], double yaw, double pitch, float* out) const {
  // Carrier rotation: yaw about z, then nose-up pitch.
  const double cy = std::cos(yaw), sy = std::sin(yaw), cp = std::cos(pitch), sp = std::sin(pitch);
  const double R[9] = {cy * cp, -sy, -cy * sp, sy * cp, cy, -sy * sp, sp, 0, cp};
  // Columns: x axis (cy cp, sy cp, sp), y axis (-sy, cy, 0), z axis (-cy sp, -sy sp, cp).
  cast_depth(rays_, pos, R, out);
}

// One depth image from a camera at `pos` whose carrier frame is the row-major rotation `R`.
void World::cast_depth(const RaySet& rays, const double pos[3], const double R[9], float* out) const {
  const int n = static_cast<int>(rays.forward_dot.size());
  const double range = robot_.depth_max_range;
  for (int i = 0; i < n; ++i) {
    const double* d = &rays.dirs[3 * i];
    double v[3];
    for (int a = 0; a < 3; ++a) v[a] = R[3 * a] * d[0] + R[3 * a + 1] * d[1] + R[3 * a + 2] * d[2];
    const double t = ray_scene(pos, v, range);
    const double depth = t < 0 ? 1.0 : t * rays.forward_dot[i] / range;
    out[i] = float(std::clamp(depth, 0.01, 1.0));
  }
}

void World::camera_pos(double pos[3]) const {
  const double* x = module_pos(0);
  const double* R = module_mat(0);
  const double off[3] = {0.5 * robot_.module_length, 0, robot_.camera_height - robot_.wheel_radius};
  for (int a = 0; a < 3; ++a) pos[a] = x[a] + R[3 * a] * off[0] + R[3 * a + 1] * off[1] + R[3 * a + 2] * off[2];
}

void World::depth_ray(int pixel, double pnt[3], double dir[3]) const {
  camera_pos(pnt);
  const double* R = module_mat(0);
  const double* d = &rays_.dirs[3 * std::size_t(pixel)];
  for (int a = 0; a < 3; ++a) dir[a] = R[3 * a] * d[0] + R[3 * a + 1] * d[1] + R[3 * a + 2] * d[2];
}

void World::render_depth(float* out) const {
  double pos[3];
  camera_pos(pos);
  cast_depth(rays_, pos, module_mat(0), out);
}

int World::depth_rows_above_horizon() const {
  const int w = robot_.depth_width;
  int rows = 0;
  for (int i = 0; i < robot_.depth_height; ++i)
    if (rays_.dirs[3 * (std::size_t(i) * w + w / 2) + 2] > 0) rows = i + 1;  // z of the level carrier frame
  return std::max(rows, 1);
}

void World::render_decision_depth(float* out) const {
  double pos[3];
  camera_pos(pos);
  cast_depth(decision_rays_, pos, module_mat(0), out);
}

void World::render_scan(float* out) const {
  if (scan_rays_.forward_dot.empty()) throw std::logic_error("World::render_scan: RobotParams::scan_columns is 0");
  double pos[3];
  camera_pos(pos);
  cast_depth(scan_rays_, pos, module_mat(0), out);
}

int World::render_view_from(double x, double y, double yaw, float* out) const {
  const double half = 0.5 * robot_.module_length;
  const double pos[3] = {x + half * std::cos(yaw), y + half * std::sin(yaw),
                         floor_height(layout_, x, y) + robot_.camera_height};
  render_depth_at(pos, yaw, 0.0, out);
  return scene_label(scene_, layout_, x, y);
}

void World::read_distances(float* out) const {
  const double range = robot_.distance_range;
  for (int k = 0; k < modules_; ++k) {
    const double* x = module_pos(k);
    const double* R = module_mat(k);
    const double dz = robot_.distance_height - robot_.wheel_radius;
    double p[3];
    for (int a = 0; a < 3; ++a) p[a] = x[a] + R[3 * a + 2] * dz;
    // Module's y axis, flattened to horizontal so that pitching on stairs does not aim at the floor.
    double y[3] = {R[1], R[4], 0};
    const double n = std::hypot(y[0], y[1]);
    if (n < 1e-9) {
      out[2 * k] = out[2 * k + 1] = 1.0f;
      continue;
    }
    y[0] /= n;
    y[1] /= n;
    const double minus_y[3] = {-y[0], -y[1], 0};
    const double tl = ray_scene(p, y, range), tr = ray_scene(p, minus_y, range);
    out[2 * k] = float(tl < 0 ? 1.0 : tl / range);
    out[2 * k + 1] = float(tr < 0 ? 1.0 : tr / range);
  }
}

}  // namespace comorph::sim
