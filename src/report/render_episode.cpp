#include "report/render_episode.hpp"

#include <filesystem>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>

namespace comorph::report {

std::string strip_path_beside(const std::string& video_path) {
  return std::filesystem::path(video_path).replace_extension().string() + "-strip.png";
}

std::vector<int> evenly_spaced(int total, int count) {
  std::vector<int> out;
  if (total <= 0 || count <= 0) return out;
  if (total <= count) {
    for (int i = 0; i < total; ++i) out.push_back(i);
    return out;
  }
  if (count == 1) return {0};
  for (int i = 0; i < count; ++i)
    out.push_back(static_cast<int>((static_cast<long long>(i) * (total - 1) + (count - 1) / 2) / (count - 1)));
  return out;
}

RenderResult render_episode(const std::function<std::optional<SimFrame>()>& next, const RenderOptions& options) {
  if (options.video_path.empty() && options.strip_path.empty())
    throw std::invalid_argument("render_episode: neither a video path nor a strip path given");
  if (options.max_frames < 1) throw std::invalid_argument("render_episode: max_frames must be >= 1");

  std::unique_ptr<VideoWriter> video;
  if (!options.video_path.empty())
    video = std::make_unique<VideoWriter>(options.video_path, options.width, options.height, options.video);

  // Keyframe candidates without holding the whole episode in memory: keep every
  // `stride`-th frame; when 2 * strip_frames are held, drop every other one and
  // double the stride. The kept frames stay evenly spaced in time.
  const size_t keep_limit = static_cast<size_t>(std::max(1, options.strip_frames)) * 2;
  std::vector<Image> kept;
  int stride = 1;

  std::unique_ptr<OffscreenRenderer> renderer;
  RenderResult result;
  while (result.frames < options.max_frames) {
    const std::optional<SimFrame> frame = next();
    if (!frame) break;
    if (!frame->model || !frame->data) throw std::invalid_argument("render_episode: frame without model or data");
    if (!renderer || renderer->model() != frame->model)
      renderer = std::make_unique<OffscreenRenderer>(frame->model, options.width, options.height);
    Image image = renderer->render(frame->data, options.camera);
    if (video) video->add_frame(image);
    if (!options.strip_path.empty() && result.frames % stride == 0) {
      kept.push_back(std::move(image));
      if (kept.size() >= keep_limit) {
        std::vector<Image> halved;
        for (size_t i = 0; i < kept.size(); i += 2) halved.push_back(std::move(kept[i]));
        kept = std::move(halved);
        stride *= 2;
      }
    }
    ++result.frames;
  }
  if (result.frames == 0) throw std::runtime_error("render_episode: the episode gave no frame to draw");
  if (renderer) result.gl_renderer = renderer->gl_renderer();
  renderer.reset();
  if (video) video->finish();
  if (!options.strip_path.empty()) {
    std::vector<Image> strip;
    for (int i : evenly_spaced(static_cast<int>(kept.size()), options.strip_frames)) strip.push_back(kept[i]);
    write_png(hstack(strip), options.strip_path, options.strip_height);
  }
  return result;
}

RenderResult render_episode(const mjModel* model, mjData* data, const std::function<bool()>& advance,
                            const RenderOptions& options) {
  bool first = true;
  return render_episode(
      [&]() -> std::optional<SimFrame> {
        if (first) {
          first = false;
          mj_forward(model, data);  // the initial state's kinematics
          return SimFrame{model, data};
        }
        if (!advance()) return std::nullopt;
        return SimFrame{model, data};
      },
      options);
}

}  // namespace comorph::report
