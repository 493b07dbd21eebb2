// Video and still images through ffmpeg: raw RGB frames are piped to an
// `ffmpeg` child process, which encodes the .mp4 or the .png. No image
// encoder of our own.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "report/offscreen_renderer.hpp"

namespace comorph::report {

struct VideoOptions {
  double fps = 31.25;             // frames a second of video (one frame per 32 ms control step)
  std::string codec = "libx264";  // ffmpeg encoder: libx264 (H.264) or mpeg4 (both in Debian's ffmpeg)
  int crf = 23;                   // libx264 quality, 0 (lossless) .. 51 (worst); ignored by mpeg4
};

class ChildInput;

// Writes frames of one size to an .mp4 through ffmpeg, into a temporary file
// beside `path` that finish() renames to `path` once ffmpeg succeeded (a
// failed or interrupted video never looks complete).
class VideoWriter {
 public:
  VideoWriter(const std::string& path, int width, int height, const VideoOptions& options = {});
  ~VideoWriter();  // finishes the file if finish() was not called (errors then only logged)
  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;

  void add_frame(const Image& frame);  // throws if the size differs from the first
  void finish();                       // closes the video; throws if ffmpeg failed
  int frames() const { return frames_; }

 private:
  std::string path_, tmp_path_;
  int width_, height_;
  int frames_ = 0;
  std::unique_ptr<ChildInput> ffmpeg_;
};

// The images side by side, left to right, on one row (all the same height).
Image hstack(const std::vector<Image>& images);

// Writes one image as PNG through ffmpeg (temporary file + rename); `height_px`
// > 0 scales it to that height.
void write_png(const Image& image, const std::string& path, int height_px = 0);

}  // namespace comorph::report
