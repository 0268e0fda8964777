#include "support/heap_policy.hpp"

#include <cstdlib>  // defines __GLIBC__ on glibc

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace drom {

void keep_freed_memory() {
#if defined(__GLIBC__)
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_ARENA_MAX, 1);
  mallopt(M_TRIM_THRESHOLD, -1);       // -1: never trim
  mallopt(M_TOP_PAD, 256 << 20);       // and the heap grown 256 MB at a time
#endif
}

}  // namespace drom
