#include "report/video.hpp"

#include <spdlog/spdlog.h>

#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <stdexcept>

#include <fmt/format.h>

#include "report/process.hpp"

namespace comorph::report {
namespace {

std::string ffmpeg_path() { return require_executable("ffmpeg", "ffmpeg"); }

void check_image(const Image& image, const char* what) {
  if (image.width < 1 || image.height < 1 ||
      image.rgb.size() != static_cast<size_t>(image.width) * image.height * 3)
    throw std::invalid_argument(fmt::format("{}: image of {} x {} px holds {} bytes, not w*h*3", what,
                                            image.width, image.height, image.rgb.size()));
}

// <dir>/<stem>.tmp-<pid><ext>: beside the target, with its extension (ffmpeg
// picks the container from it).
std::string temp_beside(const std::string& path) {
  const std::filesystem::path p(path);
  return (p.parent_path() / (p.stem().string() + ".tmp-" + std::to_string(::getpid()) + p.extension().string()))
      .string();
}

// Renames ffmpeg's finished output into place (removed when that fails).
void move_into_place(const std::string& tmp, const std::string& path) {
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw std::runtime_error(fmt::format("cannot write {}: {}", path, ec.message()));
  }
}

}  // namespace

VideoWriter::VideoWriter(const std::string& path, int width, int height, const VideoOptions& options)
    : path_(path), tmp_path_(temp_beside(path)), width_(width), height_(height) {
  if (width < 2 || height < 2) throw std::invalid_argument(fmt::format("video size {} x {} px too small", width, height));
  if (options.fps <= 0) throw std::invalid_argument(fmt::format("video fps {} must be > 0", options.fps));
  std::vector<std::string> argv = {ffmpeg_path(), "-nostdin", "-y", "-loglevel", "error",
                                   "-f", "rawvideo", "-pix_fmt", "rgb24",
                                   "-s", fmt::format("{}x{}", width, height),
                                   "-r", fmt::format("{}", options.fps), "-i", "pipe:0",
                                   // yuv420p (what players expect) needs even sizes
                                   "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2",
                                   "-c:v", options.codec, "-pix_fmt", "yuv420p"};
  if (options.codec == "libx264") {
    argv.insert(argv.end(), {"-crf", std::to_string(options.crf), "-preset", "veryfast"});
  } else {
    argv.insert(argv.end(), {"-q:v", "4"});
  }
  argv.insert(argv.end(), {"-movflags", "+faststart", tmp_path_});
  ffmpeg_ = std::make_unique<ChildInput>(argv);
}

VideoWriter::~VideoWriter() {
  if (!ffmpeg_) return;
  try {
    finish();
  } catch (const std::exception& e) {
    spdlog::error("video {}: {}", path_, e.what());
  }
}

void VideoWriter::add_frame(const Image& frame) {
  check_image(frame, "video frame");
  if (!ffmpeg_) throw std::logic_error(fmt::format("video {} already finished", path_));
  if (frame.width != width_ || frame.height != height_)
    throw std::invalid_argument(fmt::format("video {}: frame {} x {} px, expected {} x {} px", path_,
                                            frame.width, frame.height, width_, height_));
  ffmpeg_->write(frame.rgb.data(), frame.rgb.size());
  ++frames_;
}

void VideoWriter::finish() {
  if (!ffmpeg_) return;
  auto child = std::move(ffmpeg_);
  try {
    child->finish();
    if (frames_ == 0) throw std::runtime_error(fmt::format("video {}: no frames were written", path_));
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(tmp_path_, ignored);
    throw;
  }
  move_into_place(tmp_path_, path_);
}

Image hstack(const std::vector<Image>& images) {
  if (images.empty()) throw std::invalid_argument("hstack: no images");
  Image out;
  out.height = images.front().height;
  for (const auto& im : images) {
    check_image(im, "hstack");
    if (im.height != out.height) throw std::invalid_argument("hstack: images differ in height");
    out.width += im.width;
  }
  out.rgb.resize(static_cast<size_t>(out.width) * out.height * 3);
  size_t x0 = 0;
  for (const auto& im : images) {
    const size_t row = static_cast<size_t>(im.width) * 3;
    for (int y = 0; y < out.height; ++y)
      std::memcpy(&out.rgb[(static_cast<size_t>(y) * out.width + x0) * 3], &im.rgb[y * row], row);
    x0 += static_cast<size_t>(im.width);
  }
  return out;
}

void write_png(const Image& image, const std::string& path, int height_px) {
  check_image(image, "write_png");
  std::vector<std::string> argv = {ffmpeg_path(), "-nostdin", "-y", "-loglevel", "error",
                                   "-f", "rawvideo", "-pix_fmt", "rgb24",
                                   "-s", fmt::format("{}x{}", image.width, image.height),
                                   "-i", "pipe:0"};
  if (height_px > 0) argv.insert(argv.end(), {"-vf", fmt::format("scale=-2:{}", height_px)});
  const std::string tmp = temp_beside(path);
  argv.insert(argv.end(), {"-frames:v", "1", "-update", "1", "-f", "image2", "-c:v", "png", tmp});
  try {
    ChildInput ffmpeg(argv);
    ffmpeg.write(image.rgb.data(), image.rgb.size());
    ffmpeg.finish();
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw;
  }
  move_into_place(tmp, path);
}

}  // namespace comorph::report
