// comorph._runs: trained run directories from Python (docs/python.md):
// the configuration model's choice and the motion model's greedy action for
// one observation (coopt::GreedyPolicy), and `comorph eval`'s evaluation
// (coopt::evaluate summarised by report::summarize, the eval-<scenario>.json
// numbers). Links LibTorch; comorph imports it on first use.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "coopt/config.hpp"
#include "coopt/trainer.hpp"
#include "report/episode_record.hpp"
#include "report/metrics.hpp"
#include "task/multitask_env.hpp"

namespace py = pybind11;
using namespace comorph;
namespace fs = std::filesystem;

namespace {

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

coopt::CooptConfig load_run_config(const std::string& run_dir) {
  const std::string path = (fs::path(run_dir) / "config.yaml").string();
  if (!fs::exists(path)) throw std::invalid_argument(run_dir + ": not a training run (no config.yaml)");
  return coopt::load_coopt_config(path);
}

// A float array of exactly `size` values (any shape), named in the error.
const float* floats_of(const FloatArray& a, py::ssize_t size, const char* name) {
  if (a.size() != size)
    throw std::invalid_argument(std::string(name) + ": " + std::to_string(a.size()) + " floats, expected " +
                                std::to_string(size));
  return a.data();
}

class Run {
 public:
  explicit Run(const std::string& run_dir)
      : dir_(run_dir), config_(load_run_config(run_dir)), policy_(config_, run_dir),
        spec_(task::MultiTaskEnv::spec(config_.env)) {}

  int choose_modules(const FloatArray& image, int max_modules, int scene, double target_distance_m) {
    const float* p = floats_of(image, policy_.decision_image_size(), "image");
    return policy_.choose_modules(p, max_modules, scene, target_distance_m);
  }

  FloatArray act(const FloatArray& depth, const FloatArray& state, const FloatArray& clearance) {
    const float* d = floats_of(depth, py::ssize_t(spec_.depth_channels) * spec_.depth_height * spec_.depth_width, "depth");
    const float* s = floats_of(state, spec_.state_size, "state");
    const float* c = floats_of(clearance, spec_.clearance_size, "clearance");
    FloatArray out(py::ssize_t(spec_.action_size));
    policy_.act(d, s, c, out.mutable_data());
    return out;
  }

  // The run's simulator config, for comorph._core.Env (env_config=).
  py::capsule env_config() const {
    return py::capsule(new task::EnvConfig(config_.env), "comorph.EnvConfig",
                       [](PyObject* o) { delete static_cast<task::EnvConfig*>(PyCapsule_GetPointer(o, "comorph.EnvConfig")); });
  }

  const coopt::CooptConfig& config() const { return config_; }
  const std::string& dir() const { return dir_; }
  bool hierarchical() const { return policy_.hierarchical(); }

 private:
  std::string dir_;
  coopt::CooptConfig config_;
  coopt::GreedyPolicy policy_;
  task::EnvSpec spec_;
};

// The summary `comorph eval` writes as eval-<scenario>.json, as JSON text.
// episodes <= 0, seed < 0: the run config's eval section, as `comorph eval`.
std::string evaluate(const std::string& run_dir, int episodes, int seed, const std::string& scenario, int workers) {
  const coopt::CooptConfig config = load_run_config(run_dir);
  coopt::EvalRequest request;
  request.scenario = scenario;
  request.episodes = episodes > 0 ? episodes : config.eval.episodes;  // as `comorph eval`: 0 = the config's
  request.seed = seed >= 0 ? seed : config.eval.seed;
  request.workers = workers > 0 ? workers : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::vector<coopt::EpisodeLog> logs;
  {
    py::gil_scoped_release release;
    logs = coopt::evaluate(config, run_dir, request);
  }
  std::vector<report::EpisodeRecord> records(logs.begin(), logs.end());
  return report::to_json(report::summarize(records, config.env.task.objective, coopt::stair_heights(config))).dump();
}

}  // namespace

PYBIND11_MODULE(_runs, m) {
  m.doc() = "comorph's trained runs: greedy policies and evaluation (LibTorch; docs/python.md)";
  py::class_<Run>(m, "Run")
      .def(py::init<const std::string&>(), py::arg("path"))
      .def("choose_modules", &Run::choose_modules, py::arg("image"), py::arg("max_modules"), py::arg("scene"),
           py::arg("target_distance_m") = -1.0)
      .def("act", &Run::act, py::arg("depth"), py::arg("state"), py::arg("clearance"))
      .def("env_config", &Run::env_config)
      .def_property_readonly("hierarchical", &Run::hierarchical)
      .def_property_readonly("path", &Run::dir)
      .def_property_readonly("config_text", [](const Run& r) { return r.config().text; })
      .def_property_readonly("scenario", [](const Run& r) { return name_of(r.config().trainer.scenario); })
      .def_property_readonly("eval_seed", [](const Run& r) { return r.config().eval.seed; })
      .def_property_readonly("eval_episodes", [](const Run& r) { return r.config().eval.episodes; });
  m.def("evaluate", &evaluate, py::arg("path"), py::arg("episodes"), py::arg("seed"), py::arg("scenario"),
        py::arg("workers"));
}
