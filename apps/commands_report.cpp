// `comorph report ...` and `comorph render-mjcf ...`: Markdown/HTML reports of
// run directories, and headless videos of any MJCF.
#include <mujoco/mujoco.h>
#include <nlohmann/json.hpp>

#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli_numbers.hpp"
#include "coopt/config.hpp"
#include "command_registry.hpp"
#include "report/metrics.hpp"
#include "report/render_episode.hpp"
#include "report/report.hpp"

namespace {

comorph::cli::CommandRegistration registration{[](CLI::App& app) {
  // --- report ---
  auto* report = app.add_subcommand(
      "report", "write report.md and report.html: the paper's tables beside ours, training curves, configurations");
  static std::vector<std::string> runs;
  static comorph::report::ReportOptions options;
  report->add_option("runs", runs, "run directories (run.yaml, episodes.csv, eval-*.json; docs/report.md)")
      ->required()
      ->check(CLI::ExistingDirectory);
  report->add_option("--out,-o", options.out_dir, "output directory (created)")->required();
  report->add_option("--reference", options.reference_path, "paper tables YAML (default: configs/reference/paper-tables.yaml)");
  report->add_option("--window", options.curve_window, "episodes in the training curves' moving averages")
      ->capture_default_str()
      ->check(comorph::cli::whole_in(1, 1000000));
  report->callback([] {
    options.config_identity = comorph::coopt::config_identity;
    const auto result = comorph::report::write_report(runs, options);
    std::cout << "wrote " << result.markdown_path << ", " << result.html_path << " and " << result.images.size()
              << " image(s)\n";
  });

  // --- summarize ---
  auto* summarize = app.add_subcommand(
      "summarize", "summarise an episode CSV into the evaluation JSON (success per height, time, energy, F(H))");
  static std::string episodes_csv, json_out;
  static comorph::task::ObjectiveWeights weights;
  summarize->add_option("episodes", episodes_csv, "episode CSV (docs/report.md)")->required()->check(CLI::ExistingFile);
  summarize->add_option("--out,-o", json_out, "JSON to write (default: print it)");
  // The ranges of env.task.objective (task/env_config.cpp).
  summarize->add_option("--w-t", weights.w_t, "F(H) weight of time")->capture_default_str()->check(comorph::cli::finite_in(0, 100));
  summarize->add_option("--w-e", weights.w_e, "F(H) weight of energy")->capture_default_str()->check(comorph::cli::finite_in(0, 100));
  summarize->add_option("--w-d", weights.w_d, "F(H) weight of distance")->capture_default_str()->check(comorph::cli::finite_in(0, 100));
  summarize->add_option("--t-max", weights.t_max_s, "time that makes T = 1, seconds")
      ->capture_default_str()
      ->check(comorph::cli::finite_in(1e-3, 1e6));
  summarize->add_option("--energy-scale", weights.energy_scale_J, "energy that makes E = 1, joules")
      ->capture_default_str()
      ->check(comorph::cli::finite_in(1e-3, 1e9));
  summarize->callback([] {
    const auto metrics = comorph::report::summarize(comorph::report::read_episodes_csv(episodes_csv), weights);
    if (json_out.empty()) {
      std::cout << comorph::report::to_json(metrics).dump(2) << "\n";
    } else {
      comorph::report::write_metrics_json(json_out, metrics);
      std::cout << fmt::format("wrote {} ({} episodes, success avg {:.1f} %)\n", json_out, metrics.episodes,
                               100 * metrics.success_rate.at("avg"));
    }
  });

  // --- render-mjcf ---
  auto* render = app.add_subcommand(
      "render-mjcf", "step any MJCF passively and render it headless (EGL) to an .mp4 and a keyframe strip .png");
  static std::string mjcf, out;
  static int frames = 120;
  static int steps_per_frame = 0;
  static comorph::report::RenderOptions ropt;
  render->add_option("--mjcf", mjcf, "MJCF file")->required()->check(CLI::ExistingFile);
  render->add_option("--out,-o", out, "video file (.mp4); the strip goes to <out>-strip.png")->required();
  render->add_option("--frames", frames, "frames to render")->capture_default_str()->check(comorph::cli::whole_in(1, 1000000));
  render->add_option("--width", ropt.width, "frame width, pixels")->capture_default_str()->check(comorph::cli::whole_in(16, 8192));
  render->add_option("--height", ropt.height, "frame height, pixels")->capture_default_str()->check(comorph::cli::whole_in(16, 8192));
  render->add_option("--fps", ropt.video.fps, "video frames a second")->capture_default_str()->check(comorph::cli::finite_in(1, 1000));
  render->add_option("--steps-per-frame", steps_per_frame,
                     "physics steps between frames (default: as many as make 1/fps seconds)")
      ->check(comorph::cli::whole_in(1, 1000000));
  render->add_option("--track", ropt.camera.track_body, "body the camera follows (default: free camera)");
  render->add_option("--distance", ropt.camera.distance_m, "camera distance, metres")
      ->capture_default_str()
      ->check(comorph::cli::finite_in(0.01, 1000));
  render->add_option("--codec", ropt.video.codec, "ffmpeg video encoder (libx264, mpeg4)")->capture_default_str();
  render->callback([] {
    char error[1000] = "";
    std::unique_ptr<mjModel, void (*)(mjModel*)> model(mj_loadXML(mjcf.c_str(), nullptr, error, sizeof(error)),
                                                         mj_deleteModel);
    if (!model) throw std::runtime_error(fmt::format("{}: {}", mjcf, error));
    std::unique_ptr<mjData, void (*)(mjData*)> data(mj_makeData(model.get()), mj_deleteData);
    const int steps = steps_per_frame > 0
                          ? steps_per_frame
                          : std::max(1, static_cast<int>(1.0 / (ropt.video.fps * model->opt.timestep) + 0.5));
    ropt.video_path = out;
    ropt.strip_path = comorph::report::strip_path_beside(out);
    ropt.max_frames = frames;
    const auto result = comorph::report::render_episode(
        model.get(), data.get(),
        [&] {
          for (int i = 0; i < steps; ++i) mj_step(model.get(), data.get());
          return true;
        },
        ropt);
    std::cout << fmt::format("wrote {} ({} frames of {} x {} px, {} physics steps a frame, {:.2f} s simulated) and {} "
                             "(renderer: {})\n",
                             out, result.frames, ropt.width, ropt.height, steps, data->time, ropt.strip_path,
                             result.gl_renderer);
  });
}};

}  // namespace
