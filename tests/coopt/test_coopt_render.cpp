// `comorph render --run`: the replayed episode is the evaluator's episode, and
// the command (the built binary, as a user runs it) writes a video and strips
// in which the robot is visible. Needs EGL (Mesa) and ffmpeg; skipped without.
#include <gtest/gtest.h>

#include <mujoco/mujoco.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "coopt/config.hpp"
#include "coopt/trainer.hpp"
#include "report/offscreen_renderer.hpp"
#include "report/process.hpp"
#include "report/render_episode.hpp"
#include "support/test_support.hpp"
#include "task/multitask_env.hpp"

namespace comorph::coopt {
namespace {
namespace fs = std::filesystem;

const std::string kCi = std::string(COMORPH_SOURCE_DIR) + "/configs/ci.yaml";

std::string temp_dir(const std::string& name) { return test_support::fresh_temp_dir("render_" + name); }
int run_cli(const std::string& args, std::string& output) { return test_support::run_comorph(args, output); }

// A ci-preset run trained by the command line (a few seconds), as a user has one.
struct TrainedRun {
  std::string parent, dir;
  CooptConfig config;
  TrainedRun() : parent(temp_dir("run")), dir(parent + "/run") {
    std::string log;
    if (run_cli("train --config " + kCi + " --set trainer.episodes=1 --out " + dir, log) != 0)
      throw std::runtime_error("training the ci run failed: " + log);
    config = load_coopt_config(dir + "/config.yaml");
  }
  ~TrainedRun() { fs::remove_all(parent); }
};

std::string line_of(const EpisodeLog& l) {
  std::ostringstream s;
  s.precision(17);
  s << l.episode << ' ' << l.seed << ' ' << l.scenario << ' ' << l.stair_height_m << ' ' << l.obstacles << ' '
    << l.termination << ' ' << l.time_s << ' ' << l.energy_J << ' ' << l.distance_fraction << ' ' << l.return_R1
    << ' ' << l.return_R2 << ' ' << l.steps << ' ' << l.switches << ' ';
  for (int m : l.configurations) s << m << ';';
  return s.str();
}

TEST(RenderRun, ReplayedEpisodeIsTheEvaluationsEpisodeAndTheObserverSeesEveryStep) {
  const TrainedRun run;
  EvalRequest evaluation;
  evaluation.scenario = "obstacles7";
  evaluation.episodes = 3;
  evaluation.seed = run.config.eval.seed;
  evaluation.workers = 1;
  const std::vector<EpisodeLog> evaluated = evaluate(run.config, run.dir, evaluation);
  for (int i = 0; i < 3; ++i) {
    EvalEpisodeRequest replay;
    replay.scenario = evaluation.scenario;
    replay.first_seed = evaluation.seed;
    replay.index = i;
    int calls = 0, steps_seen = -1;
    const EpisodeLog log = play_evaluation_episode(run.config, run.dir, replay, [&](const task::MultiTaskEnv& env) {
      ++calls;
      steps_seen = env.step_count();
    });
    EXPECT_EQ(line_of(log), line_of(evaluated[i])) << "episode " << i;
    EXPECT_EQ(calls, log.steps + 1) << "after the reset and after every control step";
    EXPECT_EQ(steps_seen, log.steps);
  }
  // Evaluating with the observer path in between gives the same results again.
  EXPECT_EQ(line_of(evaluate(run.config, run.dir, evaluation)[2]), line_of(evaluated[2]));

  EvalEpisodeRequest higher;
  higher.first_seed = evaluation.seed;
  higher.stair_height_m = 0.07;
  EXPECT_NEAR(play_evaluation_episode(run.config, run.dir, higher, {}).stair_height_m, 0.07, 1e-12);
  higher.index = -1;
  EXPECT_THROW(play_evaluation_episode(run.config, run.dir, higher, {}), std::invalid_argument);
}

// Frame `index` of a video as RGB, decoded by ffmpeg.
report::Image video_frame(const std::string& video, int index, int width, int height, const std::string& scratch) {
  report::run_tool({"ffmpeg", "-v", "error", "-y", "-i", video, "-vf", "select=eq(n\\," + std::to_string(index) + ")",
                    "-frames:v", "1", "-f", "rawvideo", "-pix_fmt", "rgb24", scratch});
  report::Image image;
  image.width = width;
  image.height = height;
  image.rgb.resize(static_cast<std::size_t>(width) * height * 3);
  std::ifstream in(scratch, std::ios::binary);
  in.read(reinterpret_cast<char*>(image.rgb.data()), static_cast<std::streamsize>(image.rgb.size()));
  if (in.gcount() != static_cast<std::streamsize>(image.rgb.size()))
    throw std::runtime_error("ffmpeg gave " + std::to_string(in.gcount()) + " bytes for frame " + std::to_string(index));
  return image;
}

using ModelPtr = std::unique_ptr<mjModel, void (*)(mjModel*)>;
using DataPtr = std::unique_ptr<mjData, void (*)(mjData*)>;

TEST(RenderRun, CommandWritesTheVideoAndStripsAndTheRobotIsVisible) {
  if (report::find_executable("ffmpeg").empty() || report::find_executable("ffprobe").empty())
    GTEST_SKIP() << "ffmpeg/ffprobe are not installed: no video to check";
  {
    const char* probe = R"(<mujoco><worldbody><geom type="sphere" size="1"/></worldbody></mujoco>)";
    char error[1000] = "";
    const std::string xml = temp_dir("probe") + "/probe.xml";
    std::ofstream(xml) << probe;
    ModelPtr model(mj_loadXML(xml.c_str(), nullptr, error, sizeof(error)), mj_deleteModel);
    ASSERT_TRUE(model) << error;
    try {
      report::OffscreenRenderer renderer(model.get(), 8, 8);
    } catch (const std::runtime_error& e) {
      GTEST_SKIP() << "no headless OpenGL (EGL surfaceless Mesa): " << e.what();
    }
    fs::remove_all(fs::path(xml).parent_path());
  }
  const TrainedRun run;
  const int width = 160, height = 120, frames = 12;
  const int index = 1;  // evaluation episode 1
  const int seed = run.config.eval.seed + index;

  // The state of frame 0 (the episode's start): the robot's model and qpos.
  EvalEpisodeRequest replay;
  replay.first_seed = run.config.eval.seed;
  replay.index = index;
  ModelPtr model(nullptr, mj_deleteModel);
  std::vector<double> qpos;
  const EpisodeLog log = play_evaluation_episode(run.config, run.dir, replay, [&](const task::MultiTaskEnv& env) {
    if (model) return;
    model.reset(mj_copyModel(nullptr, env.world().model()));
    qpos.assign(env.world().data()->qpos, env.world().data()->qpos + model->nq);
  });
  ASSERT_TRUE(model);

  const std::string out_dir = temp_dir("video");
  const std::string video = out_dir + "/episode.mp4";
  std::string output;
  ASSERT_EQ(run_cli("render --run " + run.dir + " --seed " + std::to_string(seed) + " --out " + video +
                        " --width " + std::to_string(width) + " --height " + std::to_string(height) +
                        " --max-frames " + std::to_string(frames),
                    output),
            0)
      << output;
  const int expected_frames = std::min(frames, log.steps + 1);
  EXPECT_NE(output.find(log.termination), std::string::npos) << output;
  EXPECT_NE(output.find(std::to_string(expected_frames) + " frames"), std::string::npos) << output;
  ASSERT_TRUE(fs::is_regular_file(video));
  EXPECT_GT(fs::file_size(video), 1000u);
  const std::string strip = out_dir + "/episode-strip.png";
  const std::string run_strip = run.dir + "/render-" + std::to_string(seed) + ".png";
  for (const std::string& png : {strip, run_strip}) {
    ASSERT_TRUE(fs::is_regular_file(png)) << png;
    EXPECT_GT(fs::file_size(png), 1000u) << png;
  }
  const std::string probe = report::run_tool({"ffprobe", "-v", "error", "-count_frames", "-show_entries",
                                              "stream=width,height,nb_read_frames", "-of", "default=nw=1", video});
  EXPECT_NE(probe.find("width=" + std::to_string(width)), std::string::npos) << probe;
  EXPECT_NE(probe.find("nb_read_frames=" + std::to_string(expected_frames)), std::string::npos) << probe;

  // The same start state drawn here with the command's camera, once as it is
  // and once with the robot's geoms moved to a hidden group.
  DataPtr data(mj_makeData(model.get()), mj_deleteData);
  std::copy(qpos.begin(), qpos.end(), data->qpos);
  mj_forward(model.get(), data.get());
  report::CameraOptions camera;
  camera.track_body = "module1";
  const int root = mj_name2id(model.get(), mjOBJ_BODY, "module1");
  ASSERT_GE(root, 0);
  ModelPtr hidden(mj_copyModel(nullptr, model.get()), mj_deleteModel);
  int robot_geoms = 0;
  for (int g = 0; g < hidden->ngeom; ++g)
    if (hidden->body_rootid[hidden->geom_bodyid[g]] == hidden->body_rootid[root]) {
      hidden->geom_group[g] = 5;  // mjvOption shows groups 0..2 by default
      ++robot_geoms;
    }
  ASSERT_GT(robot_geoms, 0);
  report::Image with_robot, without_robot;
  {
    report::OffscreenRenderer renderer(model.get(), width, height);
    with_robot = renderer.render(data.get(), camera);
  }
  {
    report::OffscreenRenderer renderer(hidden.get(), width, height);
    without_robot = renderer.render(data.get(), camera);
  }
  const report::Image first = video_frame(video, 0, width, height, out_dir + "/frame0.rgb");
  // Where the robot is (the two renders differ), the video's pixel must be
  // nearer the robot's colour than the floor's: lossy H.264 blurs edges, so
  // this is asked of most robot pixels, not all.
  const int pixels = width * height;
  int robot_pixels = 0, robot_in_video = 0;
  for (std::size_t i = 0; i < with_robot.rgb.size(); i += 3) {
    int to_robot = 0, to_floor = 0, robot_vs_floor = 0;
    for (std::size_t c = i; c < i + 3; ++c) {
      robot_vs_floor += std::abs(with_robot.rgb[c] - without_robot.rgb[c]);
      to_robot += std::abs(first.rgb[c] - with_robot.rgb[c]);
      to_floor += std::abs(first.rgb[c] - without_robot.rgb[c]);
    }
    if (robot_vs_floor <= 30) continue;
    ++robot_pixels;
    if (to_robot < to_floor) ++robot_in_video;
  }
  std::printf("the robot covers %d of %d pixels; the video's first frame shows it in %d of them\n", robot_pixels,
              pixels, robot_in_video);
  EXPECT_GT(robot_pixels, pixels / 100) << "the robot should cover at least 1 % of the frame";
  EXPECT_GT(robot_in_video, robot_pixels * 8 / 10) << "the video's first frame does not show the robot";
  fs::remove_all(out_dir);
}

TEST(RenderRun, CommandRejectsBadInputBeforePlaying) {
  const std::string parent = temp_dir("bad");
  const std::string no_checkpoint = parent + "/untrained";
  fs::create_directories(no_checkpoint);
  fs::copy_file(kCi, no_checkpoint + "/config.yaml");
  const std::string out = parent + "/x.mp4";
  const auto render = [&](const std::string& run, const std::string& extra, std::string& output) {
    return run_cli("render --run " + run + " --out " + out + " " + extra, output);
  };
  std::string output;
  EXPECT_NE(render(parent + "/missing", "", output), 0);
  EXPECT_NE(output.find("not a training run (no config.yaml)"), std::string::npos) << output;
  EXPECT_NE(render(no_checkpoint, "", output), 0);
  EXPECT_NE(output.find("no checkpoint"), std::string::npos) << output;
  EXPECT_NE(render(no_checkpoint, "--scenario stairs9", output), 0);
  EXPECT_NE(output.find("unknown scenario 'stairs9'"), std::string::npos) << output;
  EXPECT_NE(render(no_checkpoint, "--seed -3", output), 0);
  EXPECT_NE(output.find("seeds are >= 0"), std::string::npos) << output;
  EXPECT_NE(render(no_checkpoint, "--seed 5", output), 0);  // ci eval.seed is 700000
  EXPECT_NE(output.find("below the run's eval.seed 700000"), std::string::npos) << output;
  EXPECT_NE(render(no_checkpoint, "--stair-height 0", output), 0);
  EXPECT_NE(output.find("--stair-height"), std::string::npos) << output;
  EXPECT_NE(render(no_checkpoint, "--frame-step 0", output), 0);
  EXPECT_NE(output.find("--frame-step"), std::string::npos) << output;
  EXPECT_FALSE(fs::exists(out));
  fs::remove_all(parent);
}

}  // namespace
}  // namespace comorph::coopt
