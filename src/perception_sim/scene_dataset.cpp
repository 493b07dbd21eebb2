// Classifier data from the simulator, and the switch delay in real episodes
// (scene_dataset.hpp).
#include "perception_sim/scene_dataset.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include "perception/scene_monitor.hpp"

namespace comorph::perception_sim {
namespace {

constexpr int kClasses = 3;  // sim::SceneLabel: stairs, obstacle field, target zone
const char* const kClassNames[kClasses] = {"stairs", "obstacle_field", "target_zone"};

// Raw mt19937_64 draws only (no std distributions): the same numbers with
// every standard library.
std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}
// One stream per (generator seed, scene seed, purpose).
std::mt19937_64 scene_rng(std::uint64_t seed, std::uint64_t scene_seed, std::uint64_t purpose) {
  return std::mt19937_64(splitmix64(splitmix64(seed) ^ splitmix64(scene_seed + 0x5151) ^ purpose));
}
double uniform01(std::mt19937_64& r) { return static_cast<double>(r() >> 11) * 0x1.0p-53; }
double uniform(std::mt19937_64& r, double a, double b) { return a + (b - a) * uniform01(r); }
int uniform_int(std::mt19937_64& r, int a, int b) {  // [a, b]
  return a + static_cast<int>(r() % static_cast<std::uint64_t>(b - a + 1));
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string range_error(const std::string& field, double value, const std::string& rule) {
  return fmt::format("{} = {} {}", field, value, rule);
}

// Empty when chains of min..max modules are ones the simulator builds.
std::string chain_range_fault(int min_modules, int max_modules) {
  if (min_modules >= kMinModules && max_modules <= kMaxModules && min_modules <= max_modules) return {};
  return fmt::format("modules [{}, {}] must be within [{}, {}] with min <= max", min_modules, max_modules,
                     kMinModules, kMaxModules);
}

// The episode of one scene seed: chain length, K, variant.
task::EpisodeSpec draw_spec(std::mt19937_64& rng, std::uint64_t scene_seed, int min_modules, int max_modules,
                            int min_obstacles, int max_obstacles) {
  task::EpisodeSpec spec;
  spec.seed = scene_seed;
  spec.configuration = make_chain(uniform_int(rng, min_modules, max_modules));
  spec.obstacles = uniform_int(rng, min_obstacles, max_obstacles);
  spec.variant = sim::Variant::standard;
  spec.stair_height = 0;  // drawn from the scene seed
  return spec;
}


// A level view's pose is usable when module 1 and its camera stand on the
// course, clear of obstacles by `margin`.
bool view_pose_ok(const task::EnvConfig& env, const sim::SceneLayout& s, double x, double y, double yaw,
                  double margin) {
  const double half = 0.5 * env.robot.module_length;
  const double points[2][2] = {{x, y}, {x + half * std::cos(yaw), y + half * std::sin(yaw)}};  // module, camera
  for (const auto& point : points) {
    const double px = point[0], py = point[1];
    const double half_width = px < s.platform_x ? 0.5 * env.scene.stair_width : 0.5 * env.scene.area_width;
    if (std::abs(py) > half_width - margin || px > s.area_end_x - margin) return false;
    for (const sim::Box& o : s.obstacles)
      if (std::abs(px - o.x) < o.hx + margin && std::abs(py - o.y) < o.hy + margin) return false;
  }
  return true;
}

}  // namespace

task::ScriptedPilot dataset_pilot() {
  task::ScriptedPilot pilot;
  // The stair gait the physics-table search picks (as `comorph demo`).
  pilot.params().gait = {1.0f, 1.0f, -0.5f, 1.0f};
  return pilot;
}

task::EpisodeSpec scene_episode(const SceneDatasetParams& p, std::uint64_t scene_seed) {
  std::mt19937_64 rng = scene_rng(p.seed, scene_seed, 1);
  return draw_spec(rng, scene_seed, p.min_modules, p.max_modules, p.min_obstacles, p.max_obstacles);
}

void parse_seed_range(const std::string& text, const std::string& what, std::uint64_t& first,
                      std::uint64_t& last) {
  auto number = [&](const std::string& t) {
    if (t.empty() || t.find_first_not_of("0123456789") != std::string::npos)
      throw std::invalid_argument(what + ": '" + text + "' is not a seed range A:B (non-negative integers, A <= B)");
    try {
      return static_cast<std::uint64_t>(std::stoull(t));
    } catch (const std::exception&) {
      throw std::invalid_argument(what + ": '" + text + "': seed out of range");
    }
  };
  const std::size_t colon = text.find(':');
  const std::uint64_t a = number(text.substr(0, colon));
  const std::uint64_t b = colon == std::string::npos ? a : number(text.substr(colon + 1));
  if (b < a) throw std::invalid_argument(what + ": '" + text + "': the last seed is below the first");
  first = a;
  last = b;
}

std::string SceneDatasetParams::validate() const {
  const std::string p = "scene dataset: ";
  if (last_seed < first_seed)
    return p + fmt::format("last_seed {} is below first_seed {}", last_seed, first_seed);
  if (frames_per_seed < 1) return p + range_error("frames_per_seed", frames_per_seed, "must be >= 1");
  if (!(run_fraction >= 0 && run_fraction <= 1)) return p + range_error("run_fraction", run_fraction, "must be in [0, 1]");
  if (std::string fault = chain_range_fault(min_modules, max_modules); !fault.empty()) return p + fault;
  if (min_obstacles < 0 || min_obstacles > max_obstacles)
    return p + fmt::format("obstacles [{}, {}] need 0 <= min <= max", min_obstacles, max_obstacles);
  if (!(mixed_fraction >= 0 && mixed_fraction <= 1))
    return p + range_error("mixed_fraction", mixed_fraction, "must be in [0, 1]");
  if (max_run_steps < 1) return p + range_error("max_run_steps", max_run_steps, "must be >= 1");
  if (!(view_yaw_spread >= 0 && view_yaw_spread <= M_PI))
    return p + range_error("view_yaw_spread", view_yaw_spread, "rad must be in [0, pi]");
  if (!(view_behind_start >= 0 && view_behind_start <= 3))
    return p + range_error("view_behind_start", view_behind_start, "m must be in [0, 3]");
  if (!(view_margin >= 0 && view_margin <= 0.5)) return p + range_error("view_margin", view_margin, "m must be in [0, 0.5]");
  return "";
}

std::size_t SceneDatasetStats::images() const {
  std::size_t n = 0;
  for (const std::size_t c : per_class()) n += c;
  return n;
}

std::vector<std::size_t> SceneDatasetStats::per_class() const {
  std::vector<std::size_t> n(kClasses, 0);
  for (int c = 0; c < kClasses; ++c) {
    if (c < static_cast<int>(run_per_class.size())) n[c] += run_per_class[c];
    if (c < static_cast<int>(view_per_class.size())) n[c] += view_per_class[c];
  }
  return n;
}

SceneDatasetStats generate_scene_frames(const task::EnvConfig& config, const SceneDatasetParams& p,
                                        const FrameSink& sink, const SeedProgress& progress) {
  if (const std::string err = p.validate(); !err.empty()) throw std::invalid_argument(err);
  if (p.max_obstacles > config.scene.max_obstacles)
    throw std::invalid_argument(fmt::format("scene dataset: max_obstacles {} exceeds the scene's max_obstacles {}",
                                            p.max_obstacles, config.scene.max_obstacles));
  const auto t0 = std::chrono::steady_clock::now();
  task::MultiTaskEnv env(config);
  const std::size_t pixels = static_cast<std::size_t>(env.depth_width()) * env.depth_height();
  const int run_quota = static_cast<int>(std::lround(p.frames_per_seed * p.run_fraction));

  SceneDatasetStats stats;
  stats.run_per_class.assign(kClasses, 0);
  stats.view_per_class.assign(kClasses, 0);
  stats.run_ends.assign(static_cast<int>(task::Termination::step_cap) + 1, 0);
  std::vector<float> frames;       // the run's depth images, step after step
  std::vector<int> labels;         // the run's labels
  std::vector<double> heads;       // the run's module 1 positions x, y (m)
  std::vector<float> view(pixels);
  const int total = static_cast<int>(p.seeds());

  for (std::uint64_t scene_seed = p.first_seed;; ++scene_seed) {
    std::mt19937_64 rng = scene_rng(p.seed, scene_seed, 1);
    task::EpisodeSpec spec = draw_spec(rng, scene_seed, p.min_modules, p.max_modules, p.min_obstacles,
                                       p.max_obstacles);
    const bool mixed_views = uniform01(rng) < p.mixed_fraction;
    env.reset(spec);
    std::vector<int> count(kClasses, 0);  // this seed's images per class

    // (a) the scripted run: every step's frame is a candidate.
    frames.clear();
    labels.clear();
    heads.clear();
    FrameInfo info;
    info.scene_seed = scene_seed;
    info.modules = env.modules();
    info.obstacles = spec.obstacles;
    if (run_quota > 0) {
      task::ScriptedPilot pilot = dataset_pilot();
      pilot.plan(env);
      auto record = [&] {
        frames.insert(frames.end(), env.depth(), env.depth() + pixels);
        labels.push_back(env.scene_label());
        heads.push_back(env.world().module_pos(0)[0]);
        heads.push_back(env.world().module_pos(0)[1]);
      };
      record();
      float action[control::kActionSize];
      control::MotionMode mode = env.mode();
      while (!env.done() && env.step_count() < p.max_run_steps) {
        pilot.act(env, action, mode);
        env.step(action, mode);
        record();
      }
      stats.run_steps += env.step_count();
      if (env.done() && env.last().reason == task::Termination::success) ++stats.runs_reached_target;
      ++stats.run_ends[env.done() ? static_cast<int>(env.last().reason) : 0];
      // Pick run_quota frames round-robin over the classes present (shuffled within a class).
      std::vector<std::vector<std::size_t>> by_class(kClasses);
      for (std::size_t i = 0; i < labels.size(); ++i) {
        if (labels[i] < 0 || labels[i] >= kClasses)
          throw std::logic_error(fmt::format("scene dataset: the env labelled a frame {}", labels[i]));
        by_class[labels[i]].push_back(i);
      }
      for (auto& v : by_class)
        for (std::size_t i = v.size(); i > 1; --i) std::swap(v[i - 1], v[rng() % i]);
      std::vector<std::size_t> picked;
      std::vector<std::size_t> next(kClasses, 0);
      for (bool any = true; any && static_cast<int>(picked.size()) < run_quota;) {
        any = false;
        for (int c = 0; c < kClasses && static_cast<int>(picked.size()) < run_quota; ++c)
          if (next[c] < by_class[c].size()) {
            picked.push_back(by_class[c][next[c]++]);
            any = true;
          }
      }
      std::sort(picked.begin(), picked.end());  // time order
      info.source = FrameSource::run;
      for (const std::size_t i : picked) {
        info.step = static_cast<int>(i);
        info.x = heads[2 * i];
        info.y = heads[2 * i + 1];
        sink(frames.data() + i * pixels, labels[i], info);
        ++count[labels[i]];
        ++stats.run_per_class[labels[i]];
      }
    }

    // (b) level views: each one of the class this seed has fewest images of.
    if (mixed_views) {
      spec.variant = sim::Variant::mixed;
      env.reset(spec);
    }
    const sim::SceneLayout& s = env.world().layout();
    const double half = 0.5 * config.robot.module_length;
    const double x_min = s.start_x - half - p.view_behind_start;
    const int views = p.frames_per_seed - (count[0] + count[1] + count[2]);
    for (int v = 0; v < views; ++v) {
      int want = 0;
      for (int c = 1; c < kClasses; ++c)
        if (count[c] < count[want]) want = c;
      double x = 0, y = 0, yaw = 0;
      bool found = false;
      for (int attempt = 0; attempt < 100000 && !found; ++attempt) {
        x = uniform(rng, x_min, s.area_end_x);
        const double half_width = x < s.platform_x ? 0.5 * config.scene.stair_width : 0.5 * config.scene.area_width;
        y = uniform(rng, -half_width, half_width);
        const double goal_yaw = x < s.platform_x ? 0.0 : std::atan2(s.target_y - y, s.target_x - x);
        yaw = goal_yaw + uniform(rng, -p.view_yaw_spread, p.view_yaw_spread);
        found = sim::scene_label(config.scene, s, x, y) == want && view_pose_ok(config, s, x, y, yaw, p.view_margin);
      }
      if (!found)
        throw std::runtime_error(fmt::format("scene dataset: seed {}: no free pose labelled {} found",
                                             scene_seed, kClassNames[want]));
      const int label = env.world().render_view_from(x, y, yaw, view.data());
      if (label != want) throw std::logic_error("scene dataset: render_view_from labels differently from scene_label");
      info.source = FrameSource::view;
      info.variant = spec.variant;
      info.step = -1;
      info.x = x;
      info.y = y;
      info.yaw = yaw;
      sink(view.data(), label, info);
      ++count[label];
      ++stats.view_per_class[label];
    }

    ++stats.seeds;
    stats.seconds = seconds_since(t0);
    if (progress) progress(stats.seeds, total, stats);
    if (scene_seed == p.last_seed) break;
  }
  return stats;
}

SceneDataset make_scene_dataset(const task::EnvConfig& env, const SceneDatasetParams& params,
                                const SeedProgress& progress) {
  SceneDataset out;
  out.data = perception::Dataset(env.robot.depth_height, env.robot.depth_width, kClasses);
  out.stats = generate_scene_frames(
      env, params,
      [&](const float* depth, int label, const FrameInfo& info) {
        out.data.add(depth, label);
        out.info.push_back(info);
      },
      progress);
  return out;
}

SceneDatasetStats write_scene_dataset(const std::string& path, const task::EnvConfig& env,
                                      const SceneDatasetParams& params, const SeedProgress& progress) {
  if (const std::string err = params.validate(); !err.empty()) throw std::invalid_argument(err);
  perception::DatasetWriter writer(path, env.robot.depth_height, env.robot.depth_width, kClasses);
  const SceneDatasetStats stats = generate_scene_frames(
      env, params, [&](const float* depth, int label, const FrameInfo&) { writer.add(depth, label); }, progress);
  writer.finish();
  return stats;
}

std::string format_class_balance(const SceneDatasetStats& st) {
  const std::vector<std::size_t> n = st.per_class();
  const std::size_t total = st.images();
  std::size_t runs = 0, views = 0;
  for (int c = 0; c < kClasses; ++c) {
    runs += c < static_cast<int>(st.run_per_class.size()) ? st.run_per_class[c] : 0;
    views += c < static_cast<int>(st.view_per_class.size()) ? st.view_per_class[c] : 0;
  }
  std::string s = fmt::format("{} images ({} from scripted runs, {} level views):", total, runs, views);
  for (int c = 0; c < kClasses; ++c)
    s += fmt::format("{} {} {} ({:.1f} %)", c ? "," : "", kClassNames[c], n[c],
                     total ? 100.0 * static_cast<double>(n[c]) / static_cast<double>(total) : 0.0);
  return s;
}

std::string format_run_ends(const SceneDatasetStats& st) {
  int runs = 0;
  std::string parts;
  for (std::size_t k = 0; k < st.run_ends.size(); ++k) {
    if (!st.run_ends[k]) continue;
    runs += st.run_ends[k];
    parts += fmt::format("{}{} {}", parts.empty() ? "" : ", ", st.run_ends[k],
                         k == 0 ? "cut at max_run_steps" : task::termination_name(static_cast<task::Termination>(k)));
  }
  return fmt::format("{} scripted runs: {}", runs, parts.empty() ? "none" : parts);
}

// ---- switch delay in real episodes ----

std::string EpisodeSwitchParams::validate() const {
  const std::string p = "episode switch evaluation: ";
  if (last_seed < first_seed) return p + fmt::format("last_seed {} is below first_seed {}", last_seed, first_seed);
  if (std::string fault = chain_range_fault(min_modules, max_modules); !fault.empty()) return p + fault;
  if (min_obstacles < 0 || min_obstacles > max_obstacles)
    return p + fmt::format("obstacles [{}, {}] need 0 <= min <= max", min_obstacles, max_obstacles);
  if (max_steps < 1) return p + range_error("max_steps", max_steps, "must be >= 1");
  return "";
}

namespace {
void pool(perception::SwitchDelayReport& into, const perception::SwitchDelayReport& one) {
  into.delays.insert(into.delays.end(), one.delays.begin(), one.delays.end());
  into.detected += one.detected;
  into.missed += one.missed;
  into.false_switches += one.false_switches;
}
double max_delay(const perception::SwitchDelayReport& r) {
  if (r.delays.empty()) return std::numeric_limits<double>::quiet_NaN();
  return static_cast<double>(*std::max_element(r.delays.begin(), r.delays.end()));
}
}  // namespace

EpisodeSwitchReport evaluate_switching_in_episodes(const task::EnvConfig& config,
                                                   perception::SceneClassifier& classifier,
                                                   const perception::SwitchDetectorParams& detector,
                                                   const EpisodeSwitchParams& p, const EpisodeProgress& progress) {
  if (const std::string err = p.validate(); !err.empty()) throw std::invalid_argument(err);
  if (const std::string err = detector.validate(); !err.empty()) throw std::invalid_argument(err);
  const perception::ClassifierParams& cp = classifier.params();
  if (cp.image_size != config.robot.depth_width || cp.image_size != config.robot.depth_height ||
      cp.classes != kClasses)
    throw std::invalid_argument(fmt::format(
        "episode switch evaluation: the classifier takes {}x{} images of {} classes; the env renders {}x{} of {}",
        cp.image_size, cp.image_size, cp.classes, config.robot.depth_height, config.robot.depth_width, kClasses));
  const auto t0 = std::chrono::steady_clock::now();
  task::MultiTaskEnv env(config);
  perception::SceneMonitor monitor(classifier, detector, 0);
  EpisodeSwitchReport report;
  const int total = static_cast<int>(p.last_seed - p.first_seed + 1);
  std::vector<int> truth;  // truth[i] = label after control step i (0 = at reset)
  for (std::uint64_t scene_seed = p.first_seed;; ++scene_seed) {
    std::mt19937_64 rng = scene_rng(p.seed, scene_seed, 2);
    env.reset(draw_spec(rng, scene_seed, p.min_modules, p.max_modules, p.min_obstacles, p.max_obstacles));
    task::ScriptedPilot pilot = dataset_pilot();
    pilot.plan(env);
    const int first = classifier.classify(env.depth(), env.depth_height(), env.depth_width());
    monitor.reset(first);
    truth.assign(1, env.scene_label());
    if (first != truth[0]) ++report.initial_wrong;
    std::vector<perception::SceneChange> declared;
    float action[control::kActionSize];
    control::MotionMode mode = env.mode();
    while (!env.done() && env.step_count() < p.max_steps) {
      pilot.act(env, action, mode);
      env.step(action, mode);
      truth.push_back(env.scene_label());
      const perception::SwitchDecision d = monitor.step(env.depth());
      if (d.switched) declared.push_back({env.step_count(), d.scene});
    }
    report.steps += env.step_count();
    if (env.done() && env.last().reason == task::Termination::success) ++report.reached_target;
    const std::vector<perception::SceneChange> changes = perception::scene_changes(truth);
    pool(report.monitor, perception::switch_delays(changes, declared));
    // The same rule on perfect labels: frames 1..n, declared step = index + 1.
    std::vector<perception::SceneChange> ideal = perception::run_detector(
        detector, truth[0], kClasses, std::vector<int>(truth.begin() + 1, truth.end()));
    for (auto& c : ideal) ++c.step;
    pool(report.rule_only, perception::switch_delays(changes, ideal));
    ++report.episodes;
    if (progress) progress(report.episodes, total);
    if (scene_seed == p.last_seed) break;
  }
  report.monitor_max_delay = max_delay(report.monitor);
  report.rule_only_max_delay = max_delay(report.rule_only);
  report.seconds = seconds_since(t0);
  return report;
}

std::string format_episode_switch_report(const EpisodeSwitchReport& r) {
  auto line = [](const char* what, const perception::SwitchDelayReport& d, double max) {
    const std::string delay = d.delays.empty() ? std::string("no delay (nothing detected)")
                                               : fmt::format("mean delay {:.1f} control steps (max {:.0f})",
                                                             d.mean_delay(), max);
    return fmt::format("  {}: {}, {} of {} scene changes detected, {} missed, {} false switches\n", what, delay,
                       d.detected, d.detected + d.missed, d.missed, d.false_switches);
  };
  return fmt::format("switch delay in {} scripted episodes ({} control steps of 32 ms, {} reached the target; "
                     "first frame misclassified in {}):\n",
                     r.episodes, r.steps, r.reached_target, r.initial_wrong) +
         line("classifier + detector", r.monitor, r.monitor_max_delay) +
         line("detector on ground-truth labels", r.rule_only, r.rule_only_max_delay);
}

}  // namespace comorph::perception_sim
