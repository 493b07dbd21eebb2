// Process-wide allocator settings for the programs that train (comorph, the benchmarks).
#pragma once

namespace comorph {

// LibTorch allocates every operation's output afresh. glibc returns a freed
// block above its mmap threshold (and a heap top above its trim threshold) to
// the kernel, so a DQN update at batch 128, whose convolution outputs are a
// few MB, faulted its pages in again on every operation: the standard preset's
// DQN refit ran 4-5 times slower in one process than in another
// (docs/coopt.md). Fixed thresholds keep freed memory in the heap for reuse.
// No effect outside glibc.
void keep_freed_memory_for_reuse();

}  // namespace comorph
