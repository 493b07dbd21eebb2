// The control step's hot path does not allocate: counted through the global
// operator new of this test binary.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "task/multitask_env.hpp"

namespace {
std::atomic<long> g_allocations{0};
}

void* operator new(std::size_t size) {
  ++g_allocations;
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

using namespace comorph;

// Parametrized on the obstacle scan: with scan_columns > 0 the clearance row
// is cast every step, into the buffer sized at construction.
class HotPath : public ::testing::TestWithParam<int> {};

TEST_P(HotPath, StepDoesNotAllocate) {
  task::EnvConfig c;
  c.robot.scan_columns = GetParam();
  const long at_start = g_allocations.load();
  task::MultiTaskEnv env(c);
  EXPECT_GT(g_allocations.load(), at_start);  // the counter sees the library's allocations
  task::EpisodeSpec spec;
  spec.seed = 6;
  spec.configuration = make_chain(6);
  env.reset(spec);
  const float a[5] = {0.8f, 0.1f, 0.5f, -0.5f, 0.5f};
  env.step(a, control::MotionMode::stair);  // warm
  const long before = g_allocations.load();
  int steps = 0;
  for (; steps < 200 && !env.done(); ++steps) {
    env.step(a, control::MotionMode::stair);
    env.metrics();
  }
  EXPECT_GT(steps, 50);
  EXPECT_EQ(g_allocations.load() - before, 0);
  // A second episode with the same chain length reuses the compiled model and buffers.
  env.reset(spec);
  const long after_reset = g_allocations.load();
  for (int i = 0; i < 20; ++i) env.step(a);
  EXPECT_EQ(g_allocations.load() - after_reset, 0);
  EXPECT_EQ(env.world().compilations(), 1);
}

INSTANTIATE_TEST_SUITE_P(ScanColumns, HotPath, ::testing::Values(0, 24));
