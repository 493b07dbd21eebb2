// Greedy evaluation of a trained run: `comorph eval`, export, the replay of
// one evaluation episode, the Python binding's GreedyPolicy.
#include <torch/torch.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <mutex>
#include <thread>

#include "common/checksum.hpp"
#include "coopt/episode_runner.hpp"
#include "coopt/run_store.hpp"
#include "coopt/segment.hpp"
#include "coopt/trainer.hpp"
#include "coopt/training_state.hpp"
#include "rl/learner.hpp"
#include "rl/policy.hpp"

namespace comorph::coopt {
namespace fs = std::filesystem;
namespace {

// The run's checkpoint, refused when it was written by another configuration.
// Also sets one torch thread per thread: evaluation threads run side by side
// and their results must not depend on how many there are.
CheckpointInfo open_checkpoint_for_evaluation(const CooptConfig& config, const std::string& run_dir) {
  CheckpointInfo info = read_checkpoint_info(run_dir);
  check_same_run(info, config, run_dir);
  rl::set_torch_threads(1, 1);
  return info;
}

// Both networks of a trained run's checkpoint, for greedy acting.
void load_greedy_agent(const CooptConfig& c, const CheckpointInfo& checkpoint, Agent& agent) {
  agent.motion = make_motion_policy(c, 1);
  load_learner_file(*agent.motion, (fs::path(checkpoint.directory) / "motion_actor.pt").string());
  agent.config = make_config_policy(c, c.trainer.holds_refit_dqn(checkpoint.episodes));
  if (agent.config) load_learner_file(*agent.config, (fs::path(checkpoint.directory) / "config_model.pt").string());
}

// Greedy episodes of a trained run: one env, scene source and copy of both
// networks (loaded from the checkpoint); one per evaluation thread.
struct GreedyPlayer {
  EpisodeRunner runner;
  Agent agent;
  task::ScriptedPilot pilot;
  LearnHooks pilot_hooks;  // learn nothing; the pilot drives (EvalRequest::pilot_drives)
  bool pilot_drives = false;

  GreedyPlayer(const CooptConfig& c, const CheckpointInfo& checkpoint, bool pilot_drives = false)
      : runner(c), pilot_drives(pilot_drives) {
    load_greedy_agent(c, checkpoint, agent);
    configure_pilot(c.trainer, pilot);
    pilot_hooks.motion = [](const rl::Observation&, const rl::Action&, float, const rl::Observation&, bool, bool, int) {};
    pilot_hooks.config = [](const rl::Observation&, const rl::Action&, float, const rl::Observation&, bool, bool, int) {};
    pilot_hooks.pilot = &pilot;
    pilot_hooks.pilot_drives = true;
  }

  // Episode `index` of an evaluation of `scenario` (spec from eval_spec).
  EpisodeLog play_episode(const task::ScenarioSpec& scenario, const task::EpisodeSpec& spec, int index,
                          const StepObserver* observe = nullptr) {
    EpisodeLog log = runner.play(agent, spec, false, pilot_drives ? &pilot_hooks : nullptr, observe);
    log.episode = index;
    log.scenario = scenario.name;
    return log;
  }
};

}  // namespace

std::vector<EpisodeLog> evaluate(const CooptConfig& run_config, const std::string& run_dir,
                                 const EvalRequest& request) {
  const task::ScenarioSpec& scenario = task::scenario_named(request.scenario);
  const CheckpointInfo info = open_checkpoint_for_evaluation(run_config, run_dir);
  CooptConfig config = run_config;  // the identity (text) stays the run's
  if (request.forced_modules != 0) {
    if (request.forced_modules < kMinModules || request.forced_modules > kMaxModules)
      throw std::invalid_argument("evaluate: forced chain of " + std::to_string(request.forced_modules) +
                                  " modules, not in [" + std::to_string(kMinModules) + ", " +
                                  std::to_string(kMaxModules) + "]");
    config.trainer.mode = TrainerMode::fixed;  // play() then drives make_chain(fixed_modules) and no DQN is loaded
    config.trainer.fixed_modules = request.forced_modules;
  }
  std::vector<EpisodeLog> logs(static_cast<std::size_t>(request.episodes));
  std::atomic<int> next{0};
  std::mutex error_mutex, progress_mutex;
  std::exception_ptr error;
  int finished = 0;
  auto work = [&] {
    try {
      GreedyPlayer player(config, info, request.pilot_drives);
      for (int i = next++; i < request.episodes; i = next++) {
        const auto spec = eval_spec(config, scenario, static_cast<std::uint64_t>(request.seed) + i, i);
        logs[static_cast<std::size_t>(i)] = player.play_episode(scenario, spec, i);
        std::lock_guard<std::mutex> lock(progress_mutex);
        ++finished;
        if (request.on_episode_finished) request.on_episode_finished(finished, request.episodes);
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      next = request.episodes;
    }
  };
  const int workers = std::max(1, std::min(request.workers, request.episodes));
  std::vector<std::thread> threads;
  for (int w = 1; w < workers; ++w) threads.emplace_back(work);
  work();
  for (auto& th : threads) th.join();
  if (error) std::rethrow_exception(error);
  return logs;
}

std::uintmax_t export_policy(const CooptConfig& config, const std::string& run_dir,
                             const std::string& out_checkpoint_dir) {
  const CheckpointInfo info = open_checkpoint_for_evaluation(config, run_dir);
  GreedyPlayer player(config, info);
  fs::create_directories(out_checkpoint_dir);
  const fs::path out(out_checkpoint_dir);
  player.agent.motion->save((out / "motion_actor.pt").string());
  if (player.agent.config) player.agent.config->save((out / "config_model.pt").string());
  fs::copy_file(fs::path(info.directory) / "trainer.yaml", out / "trainer.yaml", fs::copy_options::overwrite_existing);
  std::vector<std::string> names{"motion_actor.pt", "trainer.yaml"};
  if (player.agent.config) names.push_back("config_model.pt");
  write_checksums(out_checkpoint_dir, names);  // verified on load like a training checkpoint's
  std::uintmax_t bytes = 0;
  for (const auto& e : fs::directory_iterator(out)) bytes += fs::file_size(e.path());
  return bytes;
}

EpisodeLog play_evaluation_episode(const CooptConfig& config, const std::string& run_dir,
                                   const EvalEpisodeRequest& request, const StepObserver& observer) {
  if (request.index < 0)
    throw std::invalid_argument("play_evaluation_episode: episode index " + std::to_string(request.index) +
                                " < 0 (the stair height cycle starts at episode 0)");
  const task::ScenarioSpec& scenario = task::scenario_named(request.scenario);  // before the checkpoint loads
  const CheckpointInfo info = open_checkpoint_for_evaluation(config, run_dir);
  GreedyPlayer player(config, info);
  task::EpisodeSpec spec = eval_spec(config, scenario,
                                     static_cast<std::uint64_t>(request.first_seed) + request.index, request.index);
  if (request.stair_height_m > 0) spec.stair_height = request.stair_height_m;
  return player.play_episode(scenario, spec, request.index, observer ? &observer : nullptr);
}

struct GreedyPolicy::Impl {
  CooptConfig config;
  Agent agent;
  Buffers buffers;
};

GreedyPolicy::GreedyPolicy(const CooptConfig& config, const std::string& run_dir) : impl_(std::make_unique<Impl>()) {
  impl_->config = config;
  load_greedy_agent(config, open_checkpoint_for_evaluation(config, run_dir), impl_->agent);
  allocate_buffers(config, impl_->buffers);
}

GreedyPolicy::~GreedyPolicy() = default;

bool GreedyPolicy::hierarchical() const { return impl_->agent.config != nullptr; }

int GreedyPolicy::decision_image_size() const { return config_spec(impl_->config).image_size(); }

int GreedyPolicy::choose_modules(const float* image, int max_modules, int scene, double target_distance_m) {
  if (!impl_->agent.config) throw std::logic_error("GreedyPolicy::choose_modules: the run has no configuration model");
  if (max_modules < kMinModules || max_modules > kMaxModules)
    throw std::invalid_argument("max_modules must be in " + std::to_string(kMinModules) + ".." +
                                std::to_string(kMaxModules) + ", got " + std::to_string(max_modules));
  if (scene < 0 || scene > 2) throw std::invalid_argument("scene must be 0, 1 or 2, got " + std::to_string(scene));
  Buffers& b = impl_->buffers;
  std::copy(image, image + b.cobs.image.size(), b.cobs.image.begin());
  fill_config_vector(impl_->config.trainer, candidates()[candidate_of(max_modules)], scene, target_distance_m, b.mask,
                     b.cobs);
  impl_->agent.config->act(b.cobs, false, b.caction);
  return modules_of(b.caction.discrete);
}

void GreedyPolicy::act(const float* depth, const float* state, const float* clearance, float* action) {
  Buffers& b = impl_->buffers;
  fill_motion(depth, state, clearance, impl_->config.trainer, b.obs);
  impl_->agent.motion->act(b.obs, false, b.action);
  std::copy(b.action.continuous.begin(), b.action.continuous.end(), action);
}

}  // namespace comorph::coopt
