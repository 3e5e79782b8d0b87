#include "rff_ceres/allocator.h"

#include <cstdlib>  // Defines __GLIBC__ where it applies.

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace rff {

bool RetainFreedMemory() {
#if defined(__GLIBC__)
  // Blocks above the mmap threshold are mapped apart and unmapped on free;
  // the heap's top is trimmed above the trim threshold.
  return mallopt(M_MMAP_THRESHOLD, kMaxHeapBlockBytes) == 1 &&
         mallopt(M_TRIM_THRESHOLD, kRetainedBytes) == 1;
#else
  return false;
#endif
}

}  // namespace rff
