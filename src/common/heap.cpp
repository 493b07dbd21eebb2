#include "common/heap.hpp"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace comorph {

void keep_freed_memory_for_reuse() {
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, 32 << 20);  // glibc's largest; fixing it stops the dynamic threshold
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
}

}  // namespace comorph
