// Headless rendering on EGL surfaceless Mesa: the box must be visible (the
// image differs from the same scene without it), the tracking camera keeps it
// in view, and the video and the keyframe strip come out of ffmpeg.
#include <gtest/gtest.h>
#include <unistd.h>

#include <mujoco/mujoco.h>

#include <filesystem>
#include <fstream>
#include <memory>

#include <fmt/format.h>

#include "report/offscreen_renderer.hpp"
#include "report/process.hpp"
#include "report/render_episode.hpp"

namespace fs = std::filesystem;

namespace comorph::report {
namespace {

// A grey plane and a red box on a mocap body, so a test can move the box
// anywhere without physics; a second, free-falling green box.
const char* kScene = R"(
<mujoco>
  <visual><global offwidth="64" offheight="48"/></visual>
  <worldbody>
    <light pos="0 0 4" dir="0 0 -1"/>
    <geom type="plane" size="5 5 0.1" rgba="0.6 0.6 0.6 1"/>
    <body name="box" mocap="true" pos="0 0 0.2">
      <geom type="box" size="0.2 0.2 0.2" rgba="0.9 0.05 0.05 1" contype="0" conaffinity="0"/>
    </body>
    <body name="faller" pos="3 3 1">
      <freejoint/>
      <geom type="box" size="0.1 0.1 0.1" rgba="0.1 0.8 0.1 1"/>
    </body>
  </worldbody>
</mujoco>)";

struct Scene {
  fs::path dir;
  std::unique_ptr<mjModel, void (*)(mjModel*)> model{nullptr, mj_deleteModel};
  std::unique_ptr<mjData, void (*)(mjData*)> data{nullptr, mj_deleteData};
  Scene() {
    dir = fs::temp_directory_path() / fmt::format("comorph-render-test-{}", ::getpid());
    fs::create_directories(dir);
    std::ofstream(dir / "scene.xml") << kScene;
    char error[1000] = "";
    model.reset(mj_loadXML((dir / "scene.xml").c_str(), nullptr, error, sizeof(error)));
    if (!model) throw std::runtime_error(error);
    data.reset(mj_makeData(model.get()));
    mj_forward(model.get(), data.get());
  }
  ~Scene() { fs::remove_all(dir); }
  void move_box(double x, double y, double z) {
    data->mocap_pos[0] = x, data->mocap_pos[1] = y, data->mocap_pos[2] = z;
    mj_forward(model.get(), data.get());
  }
};

// Pixels that are clearly the red box (strong red, little green and blue).
int red_pixels(const Image& im, int x0 = 0, int y0 = 0, int x1 = -1, int y1 = -1) {
  if (x1 < 0) x1 = im.width;
  if (y1 < 0) y1 = im.height;
  int n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const auto* p = &im.rgb[(static_cast<size_t>(y) * im.width + x) * 3];
      if (p[0] > 60 && p[0] > 2 * p[1] && p[0] > 2 * p[2]) ++n;
    }
  return n;
}

int differing_pixels(const Image& a, const Image& b) {
  int n = 0;
  for (size_t i = 0; i < a.rgb.size(); i += 3)
    if (std::abs(a.rgb[i] - b.rgb[i]) + std::abs(a.rgb[i + 1] - b.rgb[i + 1]) + std::abs(a.rgb[i + 2] - b.rgb[i + 2]) > 30)
      ++n;
  return n;
}

TEST(Render, BoxIsVisibleAgainstTheSceneWithoutIt) {
  Scene s;
  // Larger than the model's 64 x 48 offscreen buffer: the renderer must enlarge it.
  OffscreenRenderer renderer(s.model.get(), 160, 120);
  EXPECT_FALSE(renderer.gl_renderer().empty());
  CameraOptions cam;  // free camera at the model centre
  cam.distance_m = 4;
  const Image with_box = renderer.render(s.data.get(), cam);
  ASSERT_EQ(with_box.rgb.size(), 160u * 120u * 3u);
  s.move_box(0, 0, -50);  // far below the floor, out of view
  const Image without_box = renderer.render(s.data.get(), cam);

  const int total = 160 * 120;
  EXPECT_GT(red_pixels(with_box), total / 100) << "the red box should cover at least 1 % of the image";
  EXPECT_EQ(red_pixels(without_box), 0);
  EXPECT_GT(differing_pixels(with_box, without_box), total / 100);
  // The same state renders the same image (the renderer keeps no stale state).
  s.move_box(0, 0, 0.2);
  EXPECT_EQ(renderer.render(s.data.get(), cam).rgb, with_box.rgb);
}

TEST(Render, TrackingCameraKeepsTheBodyCentred) {
  Scene s;
  OffscreenRenderer renderer(s.model.get(), 96, 72);
  CameraOptions tracking;
  tracking.track_body = "box";
  tracking.distance_m = 2;
  CameraOptions fixed_cam = tracking;
  fixed_cam.track_body.clear();
  fixed_cam.distance_m = 2;
  s.move_box(3, -2, 0.2);  // 3.6 m away from where the free camera looks
  const Image tracked = renderer.render(s.data.get(), tracking);
  const Image free_view = renderer.render(s.data.get(), fixed_cam);
  // Centre third of the image: the box is there only with the tracking camera.
  EXPECT_GT(red_pixels(tracked, 32, 24, 64, 48), 32 * 24 / 4);
  EXPECT_LT(red_pixels(free_view, 32, 24, 64, 48), 5);
  EXPECT_THROW(renderer.render(s.data.get(), CameraOptions{"no_such_body"}), std::invalid_argument);
}

TEST(Render, EpisodeVideoAndKeyframeStrip) {
  Scene s;
  RenderOptions opt;
  opt.width = 80;
  opt.height = 60;
  opt.camera.track_body = "faller";
  opt.camera.distance_m = 1.5;
  opt.video_path = (s.dir / "episode.mp4").string();
  opt.strip_path = (s.dir / "strip.png").string();
  opt.strip_frames = 4;
  opt.strip_height = 60;
  int steps = 0;
  const RenderResult result = render_episode(
      s.model.get(), s.data.get(),
      [&] {
        for (int i = 0; i < 16; ++i) mj_step(s.model.get(), s.data.get());
        return ++steps < 12;  // 12 calls: the initial frame + 11 advances
      },
      opt);
  EXPECT_EQ(result.frames, 12);
  ASSERT_TRUE(fs::is_regular_file(opt.video_path));
  EXPECT_GT(fs::file_size(opt.video_path), 500u);
  ASSERT_TRUE(fs::is_regular_file(opt.strip_path));
  EXPECT_GT(fs::file_size(opt.strip_path), 200u);
  // ffprobe (part of Debian's ffmpeg) reads the files back.
  const std::string video = run_tool({"ffprobe", "-v", "error", "-count_frames", "-show_entries",
                                      "stream=width,height,nb_read_frames", "-of", "default=nw=1", opt.video_path});
  EXPECT_NE(video.find("width=80"), std::string::npos) << video;
  EXPECT_NE(video.find("height=60"), std::string::npos) << video;
  EXPECT_NE(video.find("nb_read_frames=12"), std::string::npos) << video;
  const std::string strip = run_tool({"ffprobe", "-v", "error", "-show_entries", "stream=width,height", "-of",
                                      "default=nw=1", opt.strip_path});
  EXPECT_NE(strip.find("width=320"), std::string::npos) << strip;  // 4 frames of 80 px side by side
  EXPECT_NE(strip.find("height=60"), std::string::npos) << strip;
}

// A video appears under its name only once ffmpeg has finished it; one that
// ffmpeg cannot finish (an unknown encoder here; a full disk alike) leaves
// neither the file nor its temporary behind.
TEST(Render, AVideoLooksCompleteOnlyWhenItIs) {
  const fs::path dir = fs::temp_directory_path() / ("comorph_render_fail_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  {
    VideoWriter video((dir / "ok.mp4").string(), 16, 16);
    Image frame;
    frame.width = frame.height = 16;
    frame.rgb.assign(16 * 16 * 3, 100);
    for (int i = 0; i < 40; ++i) video.add_frame(frame);
    EXPECT_FALSE(fs::exists(dir / "ok.mp4"));  // ffmpeg writes a temporary file meanwhile
    video.finish();
  }
  EXPECT_TRUE(fs::is_regular_file(dir / "ok.mp4"));
  fs::remove(dir / "ok.mp4");
  EXPECT_TRUE(fs::is_empty(dir));
  VideoOptions bad;
  bad.codec = "no_such_encoder";
  EXPECT_THROW(
      {
        VideoWriter video((dir / "x.mp4").string(), 16, 16, bad);
        Image frame;
        frame.width = frame.height = 16;
        frame.rgb.assign(16 * 16 * 3, 100);
        try {
          video.add_frame(frame);
        } catch (const std::exception&) {
          // ffmpeg may have exited already; finish() reports it
        }
        video.finish();
      },
      std::runtime_error);
  EXPECT_TRUE(fs::is_empty(dir));
  fs::remove_all(dir);
}

TEST(Render, KeyframesAreEvenlySpaced) {
  EXPECT_EQ(evenly_spaced(10, 4), (std::vector<int>{0, 3, 6, 9}));
  EXPECT_EQ(evenly_spaced(3, 6), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(evenly_spaced(0, 3), std::vector<int>{});
}

TEST(Render, MissingFfmpegIsNamed) {
  const std::string saved = std::getenv("PATH") ? std::getenv("PATH") : "";
  setenv("PATH", "/nonexistent-comorph-bin", 1);
  std::string msg;
  try {
    VideoWriter video("/tmp/never.mp4", 16, 16);
  } catch (const std::runtime_error& e) {
    msg = e.what();
  }
  setenv("PATH", saved.c_str(), 1);
  EXPECT_NE(msg.find("'ffmpeg' is not installed"), std::string::npos) << msg;
}

TEST(Render, MissingToolIsNamed) {
  try {
    require_executable("comorph-no-such-tool", "some-package");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("some-package"), std::string::npos);
  }
}

}  // namespace
}  // namespace comorph::report
