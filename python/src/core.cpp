// comorph._core: task::MultiTaskEnv, a batched env stepping in C++ threads,
// and robot configurations, for the Python package around it
// (python/comorph, docs/python.md). No torch.
//
// Errors: bad arguments raise ValueError (std::invalid_argument), misuse
// (step before reset, after the end) RuntimeError, each with a message that
// names the argument, the index or the file.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <ctime>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "common/resources.hpp"
#include "env_core.hpp"
#include "morphology/configuration.hpp"
#include "task/scenario.hpp"
#include "report/offscreen_renderer.hpp"

namespace py = pybind11;
using namespace comorph;
using comorph::python::EnvCore;
using comorph::python::EnvOptions;

namespace {

using FloatArray = py::array_t<float, py::array::c_style>;

FloatArray new_array(std::vector<py::ssize_t> shape, const float* from) {
  FloatArray a(shape);
  std::memcpy(a.mutable_data(), from, sizeof(float) * static_cast<std::size_t>(a.size()));
  return a;
}

// The action as floats, checked against the action space: a 1-D array (or
// sequence) of kActionSize finite floats in [-1, 1]. `where` prefixes messages.
void read_action(const py::handle& action, float* out, const std::string& where) {
  py::array a = py::array::ensure(action);
  if (!a) throw std::invalid_argument(where + ": expected a numpy array of " +
                                      std::to_string(control::kActionSize) + " floats");
  const char kind = a.dtype().kind();
  if (kind != 'f')
    throw std::invalid_argument(where + ": dtype " + std::string(py::str(a.dtype())) +
                                ", expected a floating dtype (float32)");
  if (a.ndim() != 1 || a.shape(0) != control::kActionSize)
    throw std::invalid_argument(where + ": shape " + std::string(py::str(py::tuple(py::cast(std::vector<py::ssize_t>(
                                    a.shape(), a.shape() + a.ndim()))))) +
                                ", expected (" + std::to_string(control::kActionSize) + ",)");
  auto f = py::array_t<float, py::array::forcecast>::ensure(a);
  const auto v = f.unchecked<1>();
  for (int i = 0; i < control::kActionSize; ++i) {
    const float x = v(i);
    if (!std::isfinite(x))
      throw std::invalid_argument(where + "[" + std::to_string(i) + "] is " + std::to_string(x) + ", not finite");
    if (x < -1.0f || x > 1.0f)
      throw std::invalid_argument(where + "[" + std::to_string(i) + "] = " + std::to_string(x) +
                                  " is outside the action space [-1, 1]");
    out[i] = x;
  }
}

// Eq. 1's metrics of an ended episode, as the info keys of both envs.
struct MetricField {
  const char* key;
  double (*get)(const task::EpisodeMetrics&);
};
const MetricField kMetricFields[] = {
    {"T", [](const task::EpisodeMetrics& m) { return m.T; }},
    {"E", [](const task::EpisodeMetrics& m) { return m.E; }},
    {"D", [](const task::EpisodeMetrics& m) { return m.D; }},
    {"F", [](const task::EpisodeMetrics& m) { return m.F; }},
    {"time_s", [](const task::EpisodeMetrics& m) { return m.time_s; }},
    {"episode_energy_J", [](const task::EpisodeMetrics& m) { return m.energy_J; }},
};
constexpr const char* kEpisodeSteps = "episode_steps";

// ---------------------------------------------------------------------------
// One env.

class PyEnv {
 public:
  PyEnv(const EnvOptions& options, int render_width, int render_height)
      : core_(options), render_width_(render_width), render_height_(render_height) {
    const task::EnvSpec s = core_.env().spec();
    depth_shape_ = {s.depth_channels, s.depth_height, s.depth_width};
  }

  py::tuple reset(std::optional<std::uint64_t> seed, int modules, double stair_height) {
    core_.reset(seed, modules, stair_height);
    py::dict info;
    base_info(info);
    return py::make_tuple(observation(), info);
  }

  py::tuple step(const py::handle& action) {
    float a[control::kActionSize];
    read_action(action, a, "action");
    const task::StepOutcome* r;
    {
      py::gil_scoped_release release;
      r = &core_.step(a);
    }
    py::dict info;
    base_info(info);
    info["energy_J"] = r->energy_J;
    info["stairs_climbed_now"] = r->stairs_climbed_now;
    if (r->terminated || r->truncated) metrics_into(core_.env().metrics(), info);
    return py::make_tuple(observation(), r->reward, r->terminated, r->truncated, info);
  }

  void reconfigure(int modules) { core_.reconfigure(modules); }

  py::dict observation() const {
    const task::MultiTaskEnv& e = core_.env();
    py::dict obs;
    obs["depth"] = new_array(depth_shape_, e.depth());
    obs["state"] = new_array({task::obs::kStateSize}, e.state());
    obs["clearance"] = new_array({e.clearance_width()}, e.clearance());
    return obs;
  }

  FloatArray decision_depth() const {
    core_.require_started("decision_depth");
    const task::MultiTaskEnv& e = core_.env();
    FloatArray a({1, e.decision_depth_height(), e.decision_depth_width()});
    e.render_decision_depth(a.mutable_data());
    return a;
  }

  py::array_t<std::uint8_t> render() {
    core_.require_started("render");
    sim::World& w = core_.mutable_env().mutable_world();
    if (!renderer_ || renderer_->model() != w.model())
      renderer_ = std::make_unique<report::OffscreenRenderer>(w.model(), render_width_, render_height_);
    report::CameraOptions camera;
    camera.track_body = "module1";  // the chain's root body, as `comorph render` does
    const report::Image image = renderer_->render(w.mutable_data(), camera);
    py::array_t<std::uint8_t> out({image.height, image.width, 3});
    std::memcpy(out.mutable_data(), image.rgb.data(), image.rgb.size());
    return out;
  }

  void close() { renderer_.reset(); }

  py::dict metrics() const {
    core_.require_started("metrics");
    py::dict d;
    metrics_into(core_.env().metrics(), d);
    return d;
  }

  const EnvCore& core() const { return core_; }
  EnvCore& core() { return core_; }

 private:
  void base_info(py::dict& info) const {
    const task::MultiTaskEnv& e = core_.env();
    info["termination"] = task::termination_name(e.last().reason);
    info["scene"] = e.scene_label();
    info["modules"] = e.modules();
    info["step"] = e.step_count();
    info["seed"] = core_.episode_seed();
    info["stair_height"] = e.stair_height();
    info["stairs_climbed"] = e.stairs_climbed();
    info["target_distance_m"] = e.target_distance();
  }
  static void metrics_into(const task::EpisodeMetrics& m, py::dict& d) {
    for (const MetricField& f : kMetricFields) d[f.key] = f.get(m);
    d[kEpisodeSteps] = m.steps;
  }

  EnvCore core_;
  int render_width_, render_height_;
  std::vector<py::ssize_t> depth_shape_;
  std::unique_ptr<report::OffscreenRenderer> renderer_;
};

// ---------------------------------------------------------------------------
// A batch of envs stepped by a fixed set of threads (the calling one included).

class Workers {
 public:
  explicit Workers(int threads) {
    for (int t = 1; t < threads; ++t) threads_.emplace_back([this, t] { loop(t); });
    count_ = threads;
  }
  ~Workers() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      quit_ = true;
    }
    start_.notify_all();
    for (auto& t : threads_) t.join();
  }
  int count() const { return count_; }
  // Runs job(worker) on every worker (0 on the calling thread) and waits; rethrows the first error.
  void run(const std::function<void(int)>& job) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      job_ = &job;
      ++generation_;
      busy_ = count_ - 1;
      error_ = nullptr;
    }
    start_.notify_all();
    guarded(0);
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [this] { return busy_ == 0; });
    job_ = nullptr;
    if (error_) std::rethrow_exception(error_);
  }

 private:
  void guarded(int worker) {
    try {
      (*job_)(worker);
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!error_) error_ = std::current_exception();
    }
  }
  void loop(int worker) {
    std::uint64_t seen = 0;
    while (true) {
      {
        std::unique_lock<std::mutex> lock(mutex_);
        start_.wait(lock, [&] { return quit_ || generation_ != seen; });
        if (quit_) return;
        seen = generation_;
      }
      guarded(worker);
      {
        std::lock_guard<std::mutex> lock(mutex_);
        --busy_;
      }
      done_.notify_all();
    }
  }
  std::vector<std::thread> threads_;
  int count_ = 1;
  std::mutex mutex_;
  std::condition_variable start_, done_;
  const std::function<void(int)>* job_ = nullptr;
  std::uint64_t generation_ = 0;
  int busy_ = 0;
  bool quit_ = false;
  std::exception_ptr error_;
};

class PyVectorEnv {
 public:
  PyVectorEnv(int num_envs, int threads, const EnvOptions& options) {
    if (num_envs < 1) throw std::invalid_argument("num_envs must be >= 1, got " + std::to_string(num_envs));
    if (threads < 1) throw std::invalid_argument("threads must be >= 1, got " + std::to_string(threads));
    EnvOptions o = options;
    o.cache = std::make_shared<sim::ModelCache>(o.config.robot, o.config.scene);  // compiled once for all envs
    for (int i = 0; i < num_envs; ++i) envs_.push_back(std::make_unique<EnvCore>(o));
    final_metrics_.resize(static_cast<std::size_t>(num_envs));
    workers_ = std::make_unique<Workers>(std::min(threads, num_envs));
    const task::EnvSpec s = envs_[0]->env().spec();
    depth_size_ = s.depth_channels * s.depth_height * s.depth_width;
    clearance_size_ = s.clearance_size;
    depth_shape_ = {s.depth_channels, s.depth_height, s.depth_width};
  }

  int num_envs() const { return static_cast<int>(envs_.size()); }
  int threads() const { return workers_->count(); }

  py::tuple reset(const std::vector<std::optional<std::uint64_t>>& seeds, int modules, double stair_height) {
    const int n = num_envs();
    if (static_cast<int>(seeds.size()) != n)
      throw std::invalid_argument("reset: " + std::to_string(seeds.size()) + " seeds for " + std::to_string(n) +
                                  " envs");
    Outputs out = make_outputs(false);
    {
      py::gil_scoped_release release;
      for_each_env([&](int i) {
        envs_[i]->reset(seeds[i], modules, stair_height);
        write_observation(i, out);
      });
    }
    py::dict info;
    info["scene"] = out.scene;
    info["seed"] = out.seed;
    return py::make_tuple(out.obs, info);
  }

  py::tuple step(const py::handle& actions) {
    const int n = num_envs();
    py::array a = py::array::ensure(actions);
    if (!a || a.dtype().kind() != 'f')
      throw std::invalid_argument("actions: expected a floating numpy array (float32) of shape (" + std::to_string(n) +
                                  ", " + std::to_string(control::kActionSize) + ")");
    if (a.ndim() != 2 || a.shape(0) != n || a.shape(1) != control::kActionSize)
      throw std::invalid_argument("actions: expected shape (" + std::to_string(n) + ", " +
                                  std::to_string(control::kActionSize) + "), got ndim " + std::to_string(a.ndim()));
    for (auto& e : envs_) e->require_started("step");
    actions_.resize(static_cast<std::size_t>(n) * control::kActionSize);
    for (int i = 0; i < n; ++i)
      read_action(a[py::int_(i)], actions_.data() + std::size_t(i) * control::kActionSize,
                  "actions[" + std::to_string(i) + "]");
    Outputs out = make_outputs(true);
    {
      py::gil_scoped_release release;
      for_each_env([&](int i) {
        EnvCore& e = *envs_[i];
        const task::StepOutcome& r = e.step(actions_.data() + std::size_t(i) * control::kActionSize);
        out.reward_p[i] = r.reward;
        out.terminated_p[i] = r.terminated;
        out.truncated_p[i] = r.truncated;
        out.reason_p[i] = static_cast<int>(r.reason);
        out.energy_p[i] = r.energy_J;
        const bool ended = r.terminated || r.truncated;
        out.final_mask_p[i] = ended;
        if (ended) {
          // Same-step autoreset: the final observation and metrics go to
          // final_obs / final_info, the returned observation is the next episode's first.
          final_metrics_[i] = e.env().metrics();
          write_observation(i, out, true);
          e.reset(std::nullopt, 0, 0.0);
        }
        write_observation(i, out);
      });
    }
    py::dict info;
    info["reason"] = out.reason;
    info["scene"] = out.scene;
    info["seed"] = out.seed;
    info["energy_J"] = out.energy;
    info["_final_obs"] = out.final_mask;
    info["final_obs"] = out.final_obs;
    py::dict final_info;  // per metric an array: the ended episodes' values, NaN (steps 0) elsewhere
    for (const MetricField& f : kMetricFields) {
      py::array_t<double> column(n);
      double* p = column.mutable_data();
      for (int i = 0; i < n; ++i) p[i] = out.final_mask_p[i] ? f.get(final_metrics_[i]) : NAN;
      final_info[f.key] = column;
    }
    py::array_t<int> steps(n);
    for (int i = 0; i < n; ++i) steps.mutable_data()[i] = out.final_mask_p[i] ? final_metrics_[i].steps : 0;
    final_info[kEpisodeSteps] = steps;
    info["final_info"] = final_info;
    info["_final_info"] = out.final_mask;
    return py::make_tuple(out.obs, out.reward, out.terminated, out.truncated, info);
  }

 private:
  struct Outputs {
    py::dict obs, final_obs;
    FloatArray depth, state, clearance, f_depth, f_state, f_clearance;
    float *depth_p = nullptr, *state_p = nullptr, *clearance_p = nullptr;
    float *f_depth_p = nullptr, *f_state_p = nullptr, *f_clearance_p = nullptr;
    py::array_t<int> scene, reason;
    py::array_t<std::uint64_t> seed;
    py::array_t<double> reward, energy;
    py::array_t<bool> terminated, truncated, final_mask;
    int *scene_p = nullptr, *reason_p = nullptr;
    std::uint64_t* seed_p = nullptr;
    double *reward_p = nullptr, *energy_p = nullptr;
    bool *terminated_p = nullptr, *truncated_p = nullptr, *final_mask_p = nullptr;
  };

  Outputs make_outputs(bool stepping) {
    const py::ssize_t n = num_envs();
    Outputs o;
    auto obs_arrays = [&](py::dict& d, FloatArray& depth, FloatArray& state, FloatArray& clearance, float*& dp,
                          float*& sp, float*& cp, bool zero) {
      depth = FloatArray({n, depth_shape_[0], depth_shape_[1], depth_shape_[2]});
      state = FloatArray({n, py::ssize_t(task::obs::kStateSize)});
      clearance = FloatArray({n, py::ssize_t(clearance_size_)});
      dp = depth.mutable_data(), sp = state.mutable_data(), cp = clearance.mutable_data();
      if (zero) {
        std::fill(dp, dp + depth.size(), 0.0f);
        std::fill(sp, sp + state.size(), 0.0f);
        std::fill(cp, cp + clearance.size(), 0.0f);
      }
      d["depth"] = depth;
      d["state"] = state;
      d["clearance"] = clearance;
    };
    obs_arrays(o.obs, o.depth, o.state, o.clearance, o.depth_p, o.state_p, o.clearance_p, false);
    o.scene = py::array_t<int>(n), o.scene_p = o.scene.mutable_data();
    o.seed = py::array_t<std::uint64_t>(n), o.seed_p = o.seed.mutable_data();
    if (!stepping) return o;
    obs_arrays(o.final_obs, o.f_depth, o.f_state, o.f_clearance, o.f_depth_p, o.f_state_p, o.f_clearance_p, true);
    auto d = [n](py::array_t<double>& a, double*& p) { a = py::array_t<double>(n), p = a.mutable_data(); };
    auto b = [n](py::array_t<bool>& a, bool*& p) { a = py::array_t<bool>(n), p = a.mutable_data(); };
    d(o.reward, o.reward_p), d(o.energy, o.energy_p);
    b(o.terminated, o.terminated_p), b(o.truncated, o.truncated_p), b(o.final_mask, o.final_mask_p);
    o.reason = py::array_t<int>(n), o.reason_p = o.reason.mutable_data();
    return o;
  }

  void write_observation(int i, Outputs& o, bool final = false) const {
    const task::MultiTaskEnv& e = envs_[i]->env();
    const std::size_t d = std::size_t(depth_size_), s = task::obs::kStateSize, c = std::size_t(clearance_size_);
    std::memcpy((final ? o.f_depth_p : o.depth_p) + i * d, e.depth(), d * sizeof(float));
    std::memcpy((final ? o.f_state_p : o.state_p) + i * s, e.state(), s * sizeof(float));
    std::memcpy((final ? o.f_clearance_p : o.clearance_p) + i * c, e.clearance(), c * sizeof(float));
    if (final) return;
    o.scene_p[i] = e.scene_label();
    o.seed_p[i] = envs_[i]->episode_seed();
  }

  // Env i runs on worker i % threads: the split never depends on timing.
  void for_each_env(const std::function<void(int)>& f) {
    const int n = num_envs(), t = workers_->count();
    workers_->run([&](int w) {
      for (int i = w; i < n; i += t) f(i);
    });
  }

  std::vector<std::unique_ptr<EnvCore>> envs_;
  std::vector<task::EpisodeMetrics> final_metrics_;  // of the episodes that ended in the last step
  std::unique_ptr<Workers> workers_;
  std::vector<float> actions_;
  int depth_size_ = 0, clearance_size_ = 0;
  std::vector<py::ssize_t> depth_shape_;
};

// ---------------------------------------------------------------------------
// Configurations as numpy arrays.

using IntArray = py::array_t<std::int64_t, py::array::c_style>;

template <std::size_t R, std::size_t C>
std::array<std::array<int, C>, R> read_matrix(const py::handle& m, const char* name) {
  py::array a = py::array::ensure(m);
  if (!a) throw std::invalid_argument(std::string(name) + ": expected an array");
  if (a.ndim() != 2 || a.shape(0) != py::ssize_t(R) || a.shape(1) != py::ssize_t(C))
    throw std::invalid_argument(std::string(name) + ": expected shape (" + std::to_string(R) + ", " +
                                std::to_string(C) + ")");
  auto f = py::array_t<double, py::array::forcecast>::ensure(a);
  const auto v = f.unchecked<2>();
  std::array<std::array<int, C>, R> out{};
  for (std::size_t i = 0; i < R; ++i)
    for (std::size_t j = 0; j < C; ++j) {
      const double x = v(i, j);
      if (!std::isfinite(x) || x != std::floor(x) || std::abs(x) > 1e6)
        throw std::invalid_argument(std::string(name) + "[" + std::to_string(i) + ", " + std::to_string(j) + "] = " +
                                    std::to_string(x) + " is not a whole number");
      out[i][j] = static_cast<int>(x);
    }
  return out;
}

template <std::size_t R, std::size_t C>
IntArray write_matrix(const std::array<std::array<int, C>, R>& m) {
  IntArray a({py::ssize_t(R), py::ssize_t(C)});
  auto v = a.mutable_unchecked<2>();
  for (std::size_t i = 0; i < R; ++i)
    for (std::size_t j = 0; j < C; ++j) v(i, j) = m[i][j];
  return a;
}

Configuration to_configuration(const py::handle& C_a, const py::handle& C_s) {
  Configuration c;
  c.C_a = read_matrix<kMaxModules, kMaxModules>(C_a, "C_a");
  c.C_s = read_matrix<kMaxModules, kConnectionColumns>(C_s, "C_s");
  return c;
}

py::tuple from_configuration(const Configuration& c) { return py::make_tuple(write_matrix(c.C_a), write_matrix(c.C_s)); }

double thread_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// The C++ loop of bench/python: `steps` control steps of one env with a fixed
// action (the next episode of the seed's stream when one ends), as
// (wall seconds, this thread's CPU seconds).
py::tuple cpp_loop_seconds(const EnvOptions& options, std::uint64_t seed, int steps, const std::vector<float>& action) {
  if (action.size() != control::kActionSize) throw std::invalid_argument("action: expected 5 floats");
  double wall = 0, cpu = 0;
  {
    py::gil_scoped_release release;
    EnvCore core(options);
    core.reset(seed, 0, 0.0);
    const auto start = std::chrono::steady_clock::now();
    const double cpu_start = thread_cpu_seconds();
    for (int i = 0; i < steps; ++i) {
      const task::StepOutcome& r = core.step(action.data());
      if (r.terminated || r.truncated) core.reset(std::nullopt, 0, 0.0);
    }
    cpu = thread_cpu_seconds() - cpu_start;
    wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return py::make_tuple(wall, cpu);
}

EnvOptions env_options(const std::string& config_dir, const py::object& env_config, int modules, int obstacles,
                       bool mixed) {
  EnvOptions o;
  if (!env_config.is_none()) {
    // A task::EnvConfig from comorph._runs (a trained run's simulator config).
    auto capsule = env_config.cast<py::capsule>();
    if (std::string(capsule.name() ? capsule.name() : "") != "comorph.EnvConfig")
      throw std::invalid_argument("env_config: not a comorph.EnvConfig capsule");
    o.config = *static_cast<const task::EnvConfig*>(capsule.get_pointer());
  } else {
    o.config = task::load_env_config(config_dir);
  }
  o.modules = modules;
  o.obstacles = obstacles;
  o.variant = mixed ? sim::Variant::mixed : sim::Variant::standard;
  EnvCore::check_modules(modules, "modules");
  if (obstacles < -1 || obstacles > o.config.scene.max_obstacles)
    throw std::invalid_argument("obstacles must be in 0.." + std::to_string(o.config.scene.max_obstacles) +
                                " (or None for the scene's " + std::to_string(o.config.scene.obstacles) + "), got " +
                                std::to_string(obstacles));
  return o;
}

py::dict spec_dict(const task::EnvSpec& s, double control_period, int max_steps) {
  py::dict d;
  d["depth_shape"] = py::make_tuple(s.depth_channels, s.depth_height, s.depth_width);
  d["depth_low"] = s.depth_low;
  d["depth_high"] = s.depth_high;
  d["state_size"] = s.state_size;
  d["clearance_size"] = s.clearance_size;
  d["decision_depth_shape"] = py::make_tuple(1, s.decision_depth_height, s.decision_depth_width);
  d["action_size"] = s.action_size;
  d["action_low"] = s.action_low;
  d["action_high"] = s.action_high;
  d["min_modules"] = s.min_modules;
  d["max_modules"] = s.max_modules;
  d["control_period_s"] = control_period;
  d["max_steps"] = max_steps;
  return d;
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "comorph's C++ core: the multi-task env, a batched env and robot configurations (docs/python.md)";

  py::class_<PyEnv>(m, "Env")
      .def(py::init([](const std::string& config_dir, const py::object& env_config, int modules, int obstacles,
                       bool mixed, int render_width, int render_height) {
             return std::make_unique<PyEnv>(env_options(config_dir, env_config, modules, obstacles, mixed),
                                            render_width, render_height);
           }),
           py::arg("config_dir"), py::arg("env_config"), py::arg("modules"), py::arg("obstacles"), py::arg("mixed"),
           py::arg("render_width") = 640, py::arg("render_height") = 480)
      .def("reset", &PyEnv::reset, py::arg("seed"), py::arg("modules") = 0, py::arg("stair_height") = 0.0)
      .def("step", &PyEnv::step, py::arg("action"))
      .def("reconfigure", &PyEnv::reconfigure, py::arg("modules"))
      .def("observation", &PyEnv::observation)
      .def("decision_depth", &PyEnv::decision_depth)
      .def("render", &PyEnv::render)
      .def("close", &PyEnv::close)
      .def("metrics", &PyEnv::metrics)
      .def_property_readonly("spec", [](const PyEnv& e) {
        const auto& c = e.core().env().config();
        return spec_dict(e.core().env().spec(), c.robot.control_period, c.task.max_steps);
      })
      .def_property_readonly("modules", [](const PyEnv& e) { return e.core().env().modules(); })
      .def_property_readonly("started", [](const PyEnv& e) { return e.core().started(); })
      .def_property_readonly("done", [](const PyEnv& e) { return e.core().started() && e.core().env().done(); });

  py::class_<PyVectorEnv>(m, "VectorEnv")
      .def(py::init([](int num_envs, int threads, const std::string& config_dir, const py::object& env_config,
                       int modules, int obstacles, bool mixed) {
             return std::make_unique<PyVectorEnv>(num_envs, threads,
                                                  env_options(config_dir, env_config, modules, obstacles, mixed));
           }),
           py::arg("num_envs"), py::arg("threads"), py::arg("config_dir"), py::arg("env_config"), py::arg("modules"),
           py::arg("obstacles"), py::arg("mixed"))
      .def("reset", &PyVectorEnv::reset, py::arg("seeds"), py::arg("modules") = 0, py::arg("stair_height") = 0.0)
      .def("step", &PyVectorEnv::step, py::arg("actions"))
      .def_property_readonly("num_envs", &PyVectorEnv::num_envs)
      .def_property_readonly("threads", &PyVectorEnv::threads);

  m.def("resource_dir", [] { return resource_dir(); },
        "the directory of comorph's data files (configs/): $COMORPH_RESOURCES, else the first parent of this "
        "module that holds them");
  m.def("scenarios", [] {
    // name -> (obstacles K or None for the scene's default, mixed variant): task::kScenarios.
    py::dict out;
    for (const task::ScenarioSpec& s : task::kScenarios)
      out[py::str(s.name)] = py::make_tuple(s.obstacles < 0 ? py::object(py::none()) : py::int_(s.obstacles),
                                            s.variant == sim::Variant::mixed);
    return out;
  });
  m.def("termination_names", [] {
    std::vector<std::string> names;
    for (const auto& row : enum_names(task::Termination{})) names.push_back(row.name);
    return names;
  });
  m.def("cpp_loop_seconds",
        [](const std::string& config_dir, int modules, std::uint64_t seed, int steps, const std::vector<float>& action) {
          return cpp_loop_seconds(env_options(config_dir, py::none(), modules, -1, false), seed, steps, action);
        },
        py::arg("config_dir"), py::arg("modules"), py::arg("seed"), py::arg("steps"), py::arg("action"));

  m.def("chain", [](int n) { return from_configuration(make_chain(n)); }, py::arg("modules"));
  m.def("validate", [](const py::handle& C_a, const py::handle& C_s) { return validate(to_configuration(C_a, C_s)); });
  m.def("describe", [](const py::handle& C_a, const py::handle& C_s) {
    const Configuration c = to_configuration(C_a, C_s);
    const std::string fault = validate(c);
    if (!fault.empty()) throw std::invalid_argument(fault);
    return describe(c);
  });
  m.def("to_yaml", [](const py::handle& C_a, const py::handle& C_s) { return to_yaml(to_configuration(C_a, C_s)); });
  m.def("from_yaml_text", [](const std::string& text, const std::string& source) {
    return from_configuration(configuration_from_yaml(text, source));
  });
  m.def("load_yaml", [](const std::string& path) { return from_configuration(load_configuration(path)); });
}
