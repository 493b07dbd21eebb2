// The C++ side of test_trajectory.py: one episode of task::MultiTaskEnv driven
// by the actions on stdin, printed exactly (hexadecimal floats), so that the
// Python module's trajectory for the same seed and actions can be compared
// bit for bit.
//
//   python_trajectory_reference CONFIG_DIR SEED MODULES < actions.txt
// stdin: 5 floats a line, one line a control step. stdout, one line after the
// reset and one after each step: reward terminated truncated reason | depth | state | clearance.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "task/env_config.hpp"
#include "task/multitask_env.hpp"

using namespace comorph;

namespace {
void print_floats(const float* v, int n) {
  for (int i = 0; i < n; ++i) std::printf(" %a", static_cast<double>(v[i]));
  std::printf(" |");
}
void print_observation(const task::MultiTaskEnv& env, double reward, bool terminated, bool truncated) {
  std::printf("%a %d %d %s |", reward, terminated ? 1 : 0, truncated ? 1 : 0, task::termination_name(env.last().reason));
  const task::EnvSpec s = env.spec();
  print_floats(env.depth(), s.depth_channels * s.depth_height * s.depth_width);
  print_floats(env.state(), s.state_size);
  print_floats(env.clearance(), s.clearance_size);
  std::printf("\n");
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s CONFIG_DIR SEED MODULES < actions\n", argv[0]);
    return 2;
  }
  task::MultiTaskEnv env(task::load_env_config(argv[1]));
  task::EpisodeSpec spec;
  spec.seed = std::strtoull(argv[2], nullptr, 10);
  spec.configuration = make_chain(std::atoi(argv[3]));
  env.reset(spec);
  print_observation(env, 0.0, false, false);
  float a[control::kActionSize];
  while (!env.done()) {
    for (float& x : a)
      if (std::scanf("%f", &x) != 1) return 0;
    const task::StepOutcome& r = env.step(a);
    print_observation(env, r.reward, r.terminated, r.truncated);
  }
  return 0;
}
