// Headless MuJoCo rendering: an OpenGL context on EGL's surfaceless Mesa
// platform (no display, no GPU: llvmpipe), MuJoCo's offscreen framebuffer,
// RGB frames read back into memory.
#pragma once

#include <mujoco/mujoco.h>

#include <cstdint>
#include <string>
#include <vector>

namespace comorph::report {

// Where the camera looks from. A tracking camera follows a body, so the robot
// stays in view while it drives away.
struct CameraOptions {
  std::string track_body;    // body to follow (mjCAMERA_TRACKING); "" = free camera at the model centre
  int track_body_id = -1;    // used instead of track_body when >= 0
  double distance_m = 2.5;   // camera distance from the tracked point, metres
  double azimuth_deg = 135;  // heading around the vertical axis, degrees
  double elevation_deg = -25;  // below the horizon, degrees (negative looks down)
};

// One RGB image, rows from top to bottom, 3 bytes a pixel.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  // width * height * 3 bytes
};

// Owns one EGL context and MuJoCo rendering context for one model. Not
// copyable; use it from the thread that created it (GL contexts are per thread).
class OffscreenRenderer {
 public:
  // width x height pixels. If the model's offscreen buffer (visual/global
  // offwidth, offheight) is smaller, a larger one is made for this renderer.
  OffscreenRenderer(const mjModel* model, int width, int height);
  ~OffscreenRenderer();
  OffscreenRenderer(const OffscreenRenderer&) = delete;
  OffscreenRenderer& operator=(const OffscreenRenderer&) = delete;

  // Renders the state in `data` (kinematics must be current: after mj_step or
  // mj_forward) from the camera.
  Image render(mjData* data, const CameraOptions& camera);

  const mjModel* model() const { return model_; }
  int width() const { return width_; }
  int height() const { return height_; }
  // The OpenGL renderer string (e.g. "llvmpipe (LLVM 15.0.6, 256 bits)").
  std::string gl_renderer() const { return gl_renderer_; }

 private:
  const mjModel* model_;
  int width_, height_;
  void* egl_display_ = nullptr;
  void* egl_context_ = nullptr;
  std::string gl_renderer_;
  mjvScene scene_;
  mjrContext context_;
  mjvOption option_;
  mjvCamera camera_;
  void make_current() const;
  void init_mujoco(const mjModel* model, int width, int height);  // GL context current -> MuJoCo contexts
};

}  // namespace comorph::report
