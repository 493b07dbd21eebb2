// Rendering a whole episode to an .mp4 and a keyframe strip (.png). The caller
// owns the simulation and advances it through a callback, so this layer needs
// nothing from sim/task/coopt.
#pragma once

#include <mujoco/mujoco.h>

#include <functional>
#include <optional>
#include <string>

#include "report/offscreen_renderer.hpp"
#include "report/video.hpp"

namespace comorph::report {

struct RenderOptions {
  int width = 640;               // frame width, pixels
  int height = 480;              // frame height, pixels
  int max_frames = 4000;         // stop after this many frames even if the episode goes on
  CameraOptions camera;          // tracking camera; set camera.track_body to the robot's root body
  VideoOptions video;            // fps and codec of the .mp4
  std::string video_path;        // .mp4 to write; "" = no video
  std::string strip_path;        // keyframe strip .png; "" = no strip
  int strip_frames = 6;          // keyframes in the strip, spread evenly over the episode
  int strip_height = 240;        // strip height, pixels (frames are scaled down to it)
};

struct RenderResult {
  int frames = 0;                // frames rendered (and written to the video)
  std::string gl_renderer;       // OpenGL renderer that drew them (llvmpipe on a CPU)
};

// The simulation state to draw: the current model (it may change during an
// episode when the robot sheds modules) and its data, kinematics up to date.
struct SimFrame {
  const mjModel* model = nullptr;
  mjData* data = nullptr;
};

// Draws one frame per call of `next`. `next` advances the episode by one frame
// interval and returns the state to draw, or nullopt when the episode is over.
// It is called once before the first frame (return the initial state then).
// A new rendering context is made whenever the model pointer changes.
RenderResult render_episode(const std::function<std::optional<SimFrame>()>& next, const RenderOptions& options);

// The common case of one model: draws the initial state, then calls `advance`
// (which steps `data` by one frame interval and returns false at the episode's
// end) and draws again, until it returns false or max_frames is reached.
RenderResult render_episode(const mjModel* model, mjData* data, const std::function<bool()>& advance,
                            const RenderOptions& options);

// Where the keyframe strip of a video goes: "runs/x/ep.mp4" -> "runs/x/ep-strip.png".
std::string strip_path_beside(const std::string& video_path);

// Picks `count` items spread evenly from `total` (first and last included),
// as indices in increasing order; all of them when total <= count.
std::vector<int> evenly_spaced(int total, int count);

}  // namespace comorph::report
