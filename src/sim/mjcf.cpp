#include "sim/mjcf.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace comorph::sim {
namespace {

// Geometry of one module, relative to its axle centre (see RobotParams).
struct ModuleGeometry {
  double r, t, hx, hy, body_z, body_hz, plate_z, plate_hz;
  explicit ModuleGeometry(const RobotParams& p) {
    r = p.wheel_radius;
    t = p.plate_thickness;
    hx = 0.5 * p.module_length - t;
    hy = 0.5 * p.body_width;
    body_z = 0.5 * (p.ground_clearance + p.body_height) - r;
    body_hz = 0.5 * (p.body_height - p.ground_clearance);
    plate_z = 0.5 * (p.plate_bottom + p.plate_top) - r;
    plate_hz = 0.5 * (p.plate_top - p.plate_bottom);
  }
};

const char* kRobotGeom = "contype=\"2\" conaffinity=\"1\" group=\"1\"";
const char* kSceneGeom = "contype=\"1\" conaffinity=\"2\" group=\"0\"";

// Module `id` (1-based) and, nested in its back plate, the module docked there.
void write_module(std::string& out, const Configuration& config, int id, const RobotParams& p,
                  const ModuleGeometry& g, int depth) {
  const std::string ind(2 * depth, ' ');
  // Wheels: spheres (fast analytic contacts with planes and box edges).
  for (const char* side : {"l", "r"}) {
    const double y = side[0] == 'l' ? p.wheel_offset_y : -p.wheel_offset_y;
    out += fmt::format(
        "{0}<body name=\"wheel_{1}{2}\" pos=\"0 {3:.6g} 0\">\n"
        "{0}  <joint name=\"wheel_{1}{2}\" type=\"hinge\" axis=\"0 1 0\" armature=\"{4:.6g}\"/>\n"
        "{0}  <geom name=\"wheel_{1}{2}\" type=\"sphere\" size=\"{5:.6g}\" mass=\"{6:.6g}\" "
        "condim=\"3\" friction=\"{7:.6g} 0.005 0.0001\" rgba=\"0.15 0.15 0.15 1\" {8}/>\n"
        "{0}</body>\n",
        ind, side, id, y, p.wheel_armature, g.r, p.wheel_mass, p.friction, kRobotGeom);
  }
  const std::string hinge_attrs =
      fmt::format("type=\"hinge\" axis=\"0 1 0\" range=\"{:.6g} {:.6g}\" armature=\"{:.6g}\" damping=\"{:.6g}\"",
                  -p.hinge_range, p.hinge_range, p.hinge_armature, p.hinge_damping);
  if (id == 1) {  // module 1's front plate: never connected, carries the camera side
    out += fmt::format(
        "{0}<body name=\"front_plate1\" pos=\"{1:.6g} 0 {2:.6g}\">\n"
        "{0}  <joint name=\"front1\" {3}/>\n"
        "{0}  <geom type=\"box\" pos=\"{4:.6g} 0 0\" size=\"{4:.6g} {5:.6g} {6:.6g}\" mass=\"{7:.6g}\" "
        "rgba=\"0.9 0.6 0.1 1\" {8}/>\n"
        "{0}</body>\n",
        ind, g.hx, g.plate_z, hinge_attrs, 0.5 * g.t, g.hy, g.plate_hz, p.plate_mass, kRobotGeom);
  }
  // Back plate (and, when connected, the docked module's front plate: magnets hold them as one
  // link). validate() accepts chains only, so only the back face carries a
  // module; a module type with more faces would nest its other docked modules here too.
  const int docked = module_at_face(config, id, kBackFace);
  const bool connected = docked != 0;
  const double link_half = connected ? g.t : 0.5 * g.t;
  out += fmt::format(
      "{0}<body name=\"link{1}\" pos=\"{2:.6g} 0 {3:.6g}\">\n"
      "{0}  <joint name=\"back{1}\" {4}/>\n"
      "{0}  <geom type=\"box\" pos=\"{5:.6g} 0 0\" size=\"{6:.6g} {7:.6g} {8:.6g}\" mass=\"{9:.6g}\" "
      "rgba=\"0.9 0.6 0.1 1\" {10}/>\n",
      ind, id, -g.hx, g.plate_z, hinge_attrs, -link_half, link_half, g.hy, g.plate_hz,
      connected ? 2 * p.plate_mass : p.plate_mass, kRobotGeom);
  if (connected) {
    const int nid = docked;
    out += fmt::format(
        "{0}  <body name=\"module{1}\" pos=\"{2:.6g} 0 {3:.6g}\">\n"
        "{0}    <joint name=\"front{1}\" pos=\"{4:.6g} 0 {5:.6g}\" {6}/>\n"
        "{0}    <geom name=\"body{1}\" type=\"box\" pos=\"0 0 {7:.6g}\" size=\"{8:.6g} {9:.6g} {10:.6g}\" "
        "mass=\"{11:.6g}\" rgba=\"0.2 0.4 0.8 1\" {12}/>\n",
        ind, nid, -(g.hx + 2 * g.t), -g.plate_z, g.hx, g.plate_z, hinge_attrs, g.body_z, g.hx, g.hy,
        g.body_hz, p.body_mass, kRobotGeom);
    write_module(out, config, docked, p, g, depth + 2);
    out += ind + "  </body>\n";
  }
  out += ind + "</body>\n";
}

std::string box_geom(const std::string& name, const Box& b, const char* rgba, const char* attrs) {
  return fmt::format(
      "    <geom name=\"{}\" type=\"box\" pos=\"{:.9g} {:.9g} {:.9g}\" size=\"{:.9g} {:.9g} {:.9g}\" "
      "rgba=\"{}\" {}/>\n",
      name, b.x, b.y, b.z, b.hx, b.hy, b.hz, rgba, attrs);
}

}  // namespace

std::string build_mjcf(const Configuration& config, const RobotParams& p, const SceneParams& sp,
                       const SceneLayout& s) {
  if (std::string fault = validate(config); !fault.empty())
    throw std::invalid_argument("the simulator cannot build this configuration: " + fault);
  const int n = module_count(config);
  const ModuleGeometry g(p);
  std::string out;
  out += fmt::format(
      "<mujoco model=\"comorph_chain{0}_seed{1}\">\n"
      "  <!-- comorph: {0}-module chain, stairs {2:.3f} m, {3} obstacles, variant {4} -->\n"
      "  <compiler angle=\"radian\" autolimits=\"true\"/>\n"
      "  <option timestep=\"{5:.6g}\" integrator=\"Euler\" cone=\"pyramidal\" solver=\"Newton\" "
      "iterations=\"50\" tolerance=\"1e-8\"/>\n"
      "  <size nconmax=\"300\" njmax=\"1200\"/>\n"
      "  <visual><global offwidth=\"1280\" offheight=\"720\"/></visual>\n"
      "  <asset>\n"
      "    <texture name=\"grid\" type=\"2d\" builtin=\"checker\" rgb1=\"0.55 0.55 0.5\" "
      "rgb2=\"0.45 0.45 0.4\" width=\"256\" height=\"256\"/>\n"
      "    <material name=\"grid\" texture=\"grid\" texrepeat=\"20 20\"/>\n"
      "  </asset>\n"
      "  <worldbody>\n"
      "    <light pos=\"2 0 6\" dir=\"0 0 -1\" directional=\"true\"/>\n"
      "    <geom name=\"floor\" type=\"plane\" size=\"20 20 0.1\" pos=\"3 0 0\" material=\"grid\" "
      "friction=\"{6:.6g} 0.005 0.0001\" {7}/>\n",
      n, s.seed, s.stair_height, s.obstacles.size(), name_of(s.variant), p.physics_timestep,
      p.friction, kSceneGeom);
  for (std::size_t k = 0; k < s.steps.size(); ++k)
    out += box_geom("step" + std::to_string(k + 1), s.steps[k], "0.6 0.5 0.4 1",
                    fmt::format("friction=\"{:.6g} 0.005 0.0001\" {}", p.friction, kSceneGeom).c_str());
  for (int k = 0; k < sp.max_obstacles; ++k) {
    if (k < int(s.obstacles.size())) {
      out += box_geom("obstacle" + std::to_string(k), s.obstacles[k], "0.8 0.2 0.2 1", kSceneGeom);
    } else {  // parked slot: far below the floor, no contact, hidden group
      const double hs = 0.5 * sp.obstacle_size;
      out += box_geom("obstacle" + std::to_string(k),
                      Box{-100.0 - k, 0, -10, hs, hs, 0.5 * sp.obstacle_height}, "0.8 0.2 0.2 1",
                      "contype=\"0\" conaffinity=\"0\" group=\"5\"");
    }
  }
  // Target: a thin post the depth camera sees, and a disc of the target radius (decoration).
  out += fmt::format(
      "    <geom name=\"target\" type=\"cylinder\" size=\"0.08 0.2\" pos=\"{0:.9g} {1:.9g} {2:.9g}\" "
      "rgba=\"0.1 0.8 0.2 1\" contype=\"0\" conaffinity=\"0\" group=\"0\"/>\n"
      "    <geom name=\"target_zone\" type=\"cylinder\" size=\"{3:.6g} 0.002\" pos=\"{0:.9g} {1:.9g} {4:.9g}\" "
      "rgba=\"0.1 0.8 0.2 0.3\" contype=\"0\" conaffinity=\"0\" group=\"2\"/>\n",
      s.target_x, s.target_y, s.platform_z + 0.2, sp.target_radius, s.platform_z + 0.002);

  // Robot: module 1 at the start with its front face at start_x.
  const double x1 = s.start_x - 0.5 * p.module_length * std::cos(s.start_yaw);
  const double y1 = s.start_y - 0.5 * p.module_length * std::sin(s.start_yaw);
  out += fmt::format(
      "    <body name=\"module1\" pos=\"{0:.9g} {1:.9g} {2:.9g}\" quat=\"{3:.9g} 0 0 {4:.9g}\">\n"
      "      <freejoint name=\"root\"/>\n"
      "      <geom name=\"body1\" type=\"box\" pos=\"0 0 {5:.6g}\" size=\"{6:.6g} {7:.6g} {8:.6g}\" "
      "mass=\"{9:.6g}\" rgba=\"0.2 0.4 0.8 1\" {10}/>\n"
      "      <camera name=\"depth\" pos=\"{11:.6g} 0 {12:.6g}\" xyaxes=\"0 -1 0 {13:.6g} 0 {14:.6g}\" "
      "fovy=\"{15:.6g}\"/>\n",
      x1, y1, p.wheel_radius + 1e-4, std::cos(0.5 * s.start_yaw), std::sin(0.5 * s.start_yaw),
      g.body_z, g.hx, g.hy, g.body_hz, p.body_mass, kRobotGeom, 0.5 * p.module_length,
      p.camera_height - p.wheel_radius, std::sin(p.depth_pitch), std::cos(p.depth_pitch),
      p.depth_fov_y * 180.0 / M_PI);
  write_module(out, config, 1, p, g, 3);
  out += "    </body>\n  </worldbody>\n  <actuator>\n";
  for (int k = 1; k <= n; ++k) {
    for (const char* side : {"l", "r"})
      out += fmt::format(
          "    <general name=\"wheel_{0}{1}\" joint=\"wheel_{0}{1}\" gainprm=\"{2:.6g}\" "
          "biastype=\"affine\" biasprm=\"0 0 {3:.6g}\" ctrlrange=\"{4:.6g} {5:.6g}\" "
          "forcerange=\"{6:.6g} {7:.6g}\"/>\n",
          side, k, p.wheel_kv, -p.wheel_kv, -p.wheel_max_speed, p.wheel_max_speed,
          -p.wheel_max_torque, p.wheel_max_torque);
    for (const char* hinge : {"front", "back"})
      out += fmt::format(
          "    <general name=\"{0}{1}\" joint=\"{0}{1}\" gainprm=\"{2:.6g}\" biastype=\"affine\" "
          "biasprm=\"0 {3:.6g} {4:.6g}\" ctrlrange=\"{5:.6g} {6:.6g}\" forcerange=\"{7:.6g} {8:.6g}\"/>\n",
          hinge, k, p.hinge_kp, -p.hinge_kp, -p.hinge_kv, -p.hinge_range, p.hinge_range,
          -p.hinge_max_torque, p.hinge_max_torque);
  }
  out += "  </actuator>\n</mujoco>\n";
  return out;
}

}  // namespace comorph::sim
