// `comorph render --run runs/NAME`: one greedy evaluation episode of a trained
// run, drawn headless (EGL) to an .mp4 and a keyframe strip .png. The episode
// is played by coopt::play_evaluation_episode (the evaluator's own code) while
// an observer records the robot's model and qpos after every control step; the
// frames are drawn afterwards, so drawing cannot touch the simulation and
// the episode is exactly the one `comorph eval` scores.
#include <mujoco/mujoco.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli_numbers.hpp"
#include "cli_scenario.hpp"
#include "command_registry.hpp"
#include "coopt/config.hpp"
#include "coopt/trainer.hpp"
#include "report/process.hpp"
#include "report/render_episode.hpp"
#include "task/multitask_env.hpp"

namespace {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// The episode as the renderer needs it: a copy of every model the robot had
// (the env switches models when it sheds modules, and its models are gone with
// it) and qpos after every control step.
class EpisodeRecording {
 public:
  explicit EpisodeRecording(int max_steps) {
    frame_model_.reserve(static_cast<std::size_t>(max_steps) + 1);
    frame_qpos_.reserve(static_cast<std::size_t>(max_steps) + 1);
    reserved_frames_ = max_steps + 1;
  }

  // The StepObserver: allocates only when the model changes (once or twice an episode).
  void record(const comorph::task::MultiTaskEnv& env) {
    const mjModel* model = env.world().model();
    if (model != source_model_) {
      models_.emplace_back(mj_copyModel(nullptr, model), mj_deleteModel);
      source_model_ = model;
      // The first model has the most modules: enough room for the whole episode.
      if (qpos_.empty()) qpos_.reserve(static_cast<std::size_t>(reserved_frames_) * model->nq);
    }
    frame_model_.push_back(static_cast<int>(models_.size()) - 1);
    frame_qpos_.push_back(qpos_.size());
    const mjData* data = env.world().data();
    qpos_.insert(qpos_.end(), data->qpos, data->qpos + model->nq);
  }

  int frames() const { return static_cast<int>(frame_model_.size()); }
  int models() const { return static_cast<int>(models_.size()); }

  // Draws the recorded frames 0, step, 2 step, ... and the last one.
  comorph::report::RenderResult render(int frame_step, const comorph::report::RenderOptions& options) const {
    std::vector<std::unique_ptr<mjData, void (*)(mjData*)>> data;  // one per model: kinematics from qpos
    for (const auto& m : models_) data.emplace_back(mj_makeData(m.get()), mj_deleteData);
    int next_frame = 0;
    return comorph::report::render_episode(
        [&]() -> std::optional<comorph::report::SimFrame> {
          if (next_frame >= frames()) return std::nullopt;
          const int f = next_frame;
          const int last = frames() - 1;
          next_frame = f == last ? frames() : std::min(f + frame_step, last);
          const mjModel* m = models_[frame_model_[f]].get();
          mjData* d = data[frame_model_[f]].get();
          std::copy(qpos_.begin() + frame_qpos_[f], qpos_.begin() + frame_qpos_[f] + m->nq, d->qpos);
          mj_forward(m, d);
          return comorph::report::SimFrame{m, d};
        },
        options);
  }

 private:
  std::vector<std::unique_ptr<mjModel, void (*)(mjModel*)>> models_;
  const mjModel* source_model_ = nullptr;  // the env's model the last copy was made from
  std::vector<int> frame_model_;           // frame -> index into models_
  std::vector<std::size_t> frame_qpos_;    // frame -> offset of its qpos in qpos_
  std::vector<double> qpos_;
  int reserved_frames_ = 0;
};

struct RenderRequest {
  std::string run_dir;
  long long seed = 0;  // not given: the run's eval.seed (evaluation episode 0)
  std::string scenario = "default";
  double stair_height_m = 0;  // 0: the evaluation's height for the seed
  std::string out;
  int frame_step = 1;
  comorph::report::RenderOptions options;
};

void render_run(RenderRequest r, bool seed_given, bool stair_height_given) {
  // Everything that can fail on bad input fails before the episode runs.
  const std::string config_path = (fs::path(r.run_dir) / "config.yaml").string();
  if (!fs::exists(config_path)) throw std::runtime_error(r.run_dir + ": not a training run (no config.yaml)");
  if (seed_given && r.seed < 0) throw std::runtime_error(fmt::format("--seed {}: seeds are >= 0", r.seed));
  if (stair_height_given && !(r.stair_height_m > 0 && r.stair_height_m < 1))
    throw std::runtime_error(fmt::format("--stair-height {} m: give a height in (0, 1) m", r.stair_height_m));
  if (r.frame_step < 1) throw std::runtime_error("--frame-step must be >= 1");
  if (r.options.max_frames < 1) throw std::runtime_error("--max-frames must be >= 1");
  const fs::path out_dir = fs::absolute(r.out).parent_path();
  if (!fs::is_directory(out_dir)) throw std::runtime_error(out_dir.string() + ": no such directory for --out");
  const comorph::coopt::CooptConfig config = comorph::coopt::load_coopt_config(config_path);

  // Seed -> evaluation episode: `comorph eval` gives episode i the seed
  // eval.seed + i and the stair height heights[i % 3].
  const int eval_seed = config.eval.seed;
  if (!seed_given) r.seed = eval_seed;
  if (r.seed > INT_MAX) throw std::runtime_error(fmt::format("--seed {}: seeds go up to {}", r.seed, INT_MAX));
  comorph::coopt::EvalEpisodeRequest episode;
  episode.scenario = r.scenario;
  episode.stair_height_m = stair_height_given ? r.stair_height_m : 0;
  if (r.seed >= eval_seed) {
    episode.first_seed = eval_seed;
    episode.index = static_cast<int>(r.seed - eval_seed);
  } else if (stair_height_given) {
    episode.first_seed = static_cast<int>(r.seed);
    episode.index = 0;
  } else {
    throw std::runtime_error(fmt::format(
        "--seed {} is below the run's eval.seed {}: only seeds of evaluation episodes (eval.seed + i) have a "
        "stair height; give --stair-height H for other seeds",
        r.seed, eval_seed));
  }
  comorph::coopt::read_checkpoint_info(r.run_dir);  // throws "no checkpoint" with the expected path
  comorph::report::require_executable("ffmpeg", "ffmpeg");  // before the episode, not after it

  EpisodeRecording recording(config.env.task.max_steps);
  const auto episode_start = Clock::now();
  const comorph::coopt::EpisodeLog log = comorph::coopt::play_evaluation_episode(
      config, r.run_dir, episode, [&recording](const comorph::task::MultiTaskEnv& env) { recording.record(env); });
  const double episode_s = seconds_since(episode_start);
  std::printf("%s, scenario %s, seed %lld%s: stairs %.2f m, %d obstacles\n", r.run_dir.c_str(), r.scenario.c_str(),
              r.seed,
              stair_height_given ? " (stair height given)"
                                 : fmt::format(" (evaluation episode {})", episode.index).c_str(),
              log.stair_height_m, log.obstacles);
  std::printf("outcome: %s after %.2f s (%d control steps), energy %.0f J, configurations %s (%.1f s wall)\n",
              log.termination.c_str(), log.time_s, log.steps, log.energy_J,
              comorph::task::configuration_sequence(log.configurations).c_str(), episode_s);

  // Strip beside the video, and in the run directory where `comorph report`
  // picks up render*.png (named after what makes the episode).
  r.options.video_path = r.out;
  r.options.strip_path = comorph::report::strip_path_beside(r.out);
  r.options.camera.track_body = "module1";  // the chain's root body: the robot stays centred
  r.options.video.fps = 1.0 / (config.env.robot.control_period * r.frame_step);
  std::string run_strip = fmt::format("render-{}", r.seed);
  if (comorph::task::scenario_named(r.scenario).value != comorph::task::Scenario::standard)
    run_strip += "-" + r.scenario;
  if (stair_height_given) run_strip += fmt::format("-{:.3g}m", r.stair_height_m);
  run_strip = (fs::path(r.run_dir) / (run_strip + ".png")).string();

  const auto render_start = Clock::now();
  const comorph::report::RenderResult result = recording.render(r.frame_step, r.options);
  const double render_s = seconds_since(render_start);
  fs::copy_file(r.options.strip_path, run_strip, fs::copy_options::overwrite_existing);
  const std::string every =
      r.frame_step == 1 ? std::string("every control step") : fmt::format("every {} control steps", r.frame_step);
  std::printf("wrote %s (%d frames of %d x %d px at %.4g fps, %s, %d robot model%s), %s and %s\n", r.out.c_str(),
              result.frames, r.options.width, r.options.height, r.options.video.fps, every.c_str(),
              recording.models(), recording.models() == 1 ? "" : "s", r.options.strip_path.c_str(),
              run_strip.c_str());
  std::printf("rendering: %.1f s wall (%.0f ms a frame), renderer %s\n", render_s,
              result.frames > 0 ? 1000.0 * render_s / result.frames : 0.0, result.gl_renderer.c_str());
}

comorph::cli::CommandRegistration registration{[](CLI::App& app) {
  auto* render = app.add_subcommand(
      "render", "one greedy evaluation episode of a trained run, headless (EGL), to an .mp4 and a keyframe strip");
  static RenderRequest request;
  render->add_option("--run", request.run_dir, "run directory (config.yaml, checkpoint/)")->required();
  auto* seed = render->add_option("--seed", request.seed,
                     "episode seed; eval.seed + i is evaluation episode i (default: eval.seed, episode 0)");
  auto* height = render->add_option("--stair-height", request.stair_height_m, "stair height, m (default: the episode's)")
                     ->check(comorph::cli::finite_in(0, 0.3));
  comorph::cli::add_scenario_option(render, request.scenario)->capture_default_str();
  render->add_option("--out,-o", request.out, "video file (.mp4); the strip goes to <out>-strip.png")->required();
  render->add_option("--width", request.options.width, "frame width, pixels")
      ->capture_default_str()
      ->check(comorph::cli::whole_in(16, 8192));
  render->add_option("--height", request.options.height, "frame height, pixels")
      ->capture_default_str()
      ->check(comorph::cli::whole_in(16, 8192));
  render->add_option("--max-frames", request.options.max_frames, "stop after this many frames")
      ->capture_default_str()
      ->check(comorph::cli::whole_in(1, 10000000));
  render->add_option("--frame-step", request.frame_step, "draw every Nth control step (fps divided by N)")
      ->capture_default_str()
      ->check(comorph::cli::whole_in(1, 100000));
  render->callback([seed, height] { render_run(request, seed->count() > 0, height->count() > 0); });
}};

}  // namespace
