#include "report/offscreen_renderer.hpp"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/gl.h>

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

namespace comorph::report {
namespace {

std::string egl_error(const char* what) { return fmt::format("{} failed (EGL error 0x{:x})", what, eglGetError()); }

// The surfaceless Mesa platform needs no X server and no GPU device.
EGLDisplay open_display() {
  auto get_platform_display =
      reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
  EGLDisplay display = EGL_NO_DISPLAY;
  if (get_platform_display)
    display = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (display == EGL_NO_DISPLAY)
    throw std::runtime_error(
        "no EGL surfaceless display: install the Debian packages libegl-mesa0 and libgl1-mesa-dri "
        "(scripts/install-deps.sh)");
  EGLint major = 0, minor = 0;
  if (!eglInitialize(display, &major, &minor)) throw std::runtime_error(egl_error("eglInitialize"));
  return display;
}

EGLConfig choose_config(EGLDisplay display) {
  // MuJoCo renders into its own framebuffer object, so the config needs no
  // surface type; it must support desktop OpenGL.
  const EGLint attributes[] = {EGL_RED_SIZE,   8, EGL_GREEN_SIZE,      8,
                               EGL_BLUE_SIZE,  8, EGL_ALPHA_SIZE,      8,
                               EGL_DEPTH_SIZE, 24, EGL_STENCIL_SIZE,   8,
                               EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE, 0,
                               EGL_NONE};
  EGLConfig config = nullptr;
  EGLint count = 0;
  if (!eglChooseConfig(display, attributes, &config, 1, &count) || count < 1)
    throw std::runtime_error(egl_error("eglChooseConfig (RGBA8, depth 24, desktop OpenGL)"));
  return config;
}

}  // namespace

OffscreenRenderer::OffscreenRenderer(const mjModel* model, int width, int height)
    : model_(model), width_(width), height_(height) {
  if (!model) throw std::invalid_argument("OffscreenRenderer: model is null");
  if (width < 1 || height < 1 || width > 8192 || height > 8192)
    throw std::invalid_argument(fmt::format("OffscreenRenderer: bad size {} x {} px", width, height));

  EGLDisplay display = open_display();
  egl_display_ = display;
  if (!eglBindAPI(EGL_OPENGL_API)) throw std::runtime_error(egl_error("eglBindAPI(EGL_OPENGL_API)"));
  EGLContext context = eglCreateContext(display, choose_config(display), EGL_NO_CONTEXT, nullptr);
  if (context == EGL_NO_CONTEXT) throw std::runtime_error(egl_error("eglCreateContext"));
  egl_context_ = context;
  mjv_defaultScene(&scene_);
  mjr_defaultContext(&context_);
  mjv_defaultOption(&option_);
  mjv_defaultCamera(&camera_);
  try {
    init_mujoco(model, width, height);
  } catch (...) {
    mjv_freeScene(&scene_);  // safe on a default scene
    eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display, context);
    throw;
  }
}

void OffscreenRenderer::init_mujoco(const mjModel* model, int width, int height) {
  make_current();
  if (const auto* r = glGetString(GL_RENDERER)) gl_renderer_ = reinterpret_cast<const char*>(r);

  // The offscreen buffer size comes from the model; enlarge it on a copy when
  // the requested frame does not fit, so the caller's model stays untouched.
  mjModel* sized = nullptr;
  if (model->vis.global.offwidth < width || model->vis.global.offheight < height) {
    sized = mj_copyModel(nullptr, model);
    sized->vis.global.offwidth = std::max(width, model->vis.global.offwidth);
    sized->vis.global.offheight = std::max(height, model->vis.global.offheight);
  }
  mjv_makeScene(model, &scene_, 2000);
  mjr_makeContext(sized ? sized : model, &context_, mjFONTSCALE_100);
  if (sized) mj_deleteModel(sized);
  mjr_setBuffer(mjFB_OFFSCREEN, &context_);
  if (context_.currentBuffer != mjFB_OFFSCREEN) {
    mjr_freeContext(&context_);
    throw std::runtime_error("MuJoCo could not select its offscreen framebuffer");
  }
}

OffscreenRenderer::~OffscreenRenderer() {
  make_current();
  mjr_freeContext(&context_);
  mjv_freeScene(&scene_);
  auto display = static_cast<EGLDisplay>(egl_display_);
  eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(display, static_cast<EGLContext>(egl_context_));
  // The display is shared by every renderer of the process: not terminated here.
}

void OffscreenRenderer::make_current() const {
  if (!eglMakeCurrent(static_cast<EGLDisplay>(egl_display_), EGL_NO_SURFACE, EGL_NO_SURFACE,
                      static_cast<EGLContext>(egl_context_)))
    throw std::runtime_error(egl_error("eglMakeCurrent (surfaceless)"));
}

Image OffscreenRenderer::render(mjData* data, const CameraOptions& camera) {
  make_current();
  int body = camera.track_body_id;
  if (body < 0 && !camera.track_body.empty()) {
    body = mj_name2id(model_, mjOBJ_BODY, camera.track_body.c_str());
    if (body < 0) throw std::invalid_argument(fmt::format("no body named '{}' to track", camera.track_body));
  }
  if (body >= model_->nbody) throw std::invalid_argument(fmt::format("no body with id {} to track", body));
  if (body >= 0) {
    camera_.type = mjCAMERA_TRACKING;
    camera_.trackbodyid = body;
  } else {
    mjv_defaultFreeCamera(model_, &camera_);
  }
  camera_.distance = camera.distance_m;
  camera_.azimuth = camera.azimuth_deg;
  camera_.elevation = camera.elevation_deg;
  if (body >= 0) {
    // A tracking camera moves its look-at point towards the body's subtree
    // centre of mass gradually; start it there so the first frame is framed.
    for (int i = 0; i < 3; ++i) camera_.lookat[i] = data->subtree_com[3 * body + i];
  }

  mjv_updateScene(model_, data, &option_, nullptr, &camera_, mjCAT_ALL, &scene_);
  const mjrRect viewport{0, 0, width_, height_};
  mjr_render(viewport, &scene_, &context_);

  Image image;
  image.width = width_;
  image.height = height_;
  std::vector<std::uint8_t> bottom_up(static_cast<size_t>(width_) * height_ * 3);
  mjr_readPixels(bottom_up.data(), nullptr, viewport, &context_);
  // OpenGL rows run bottom to top; images (ffmpeg, PNG) run top to bottom.
  image.rgb.resize(bottom_up.size());
  const size_t row = static_cast<size_t>(width_) * 3;
  for (int y = 0; y < height_; ++y)
    std::memcpy(&image.rgb[static_cast<size_t>(y) * row], &bottom_up[static_cast<size_t>(height_ - 1 - y) * row], row);
  return image;
}

}  // namespace comorph::report
