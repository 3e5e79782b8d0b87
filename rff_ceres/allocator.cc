#include "rff_ceres/allocator.h"

#include <cstdlib>  // Defines __GLIBC__ where it applies.
#include <cstring>

#if defined(__GLIBC__)
#include <malloc.h>
#include <sys/mman.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <vector>
#endif

namespace rff {

#if defined(__GLIBC__)
namespace {

// The process's settings for HeapReserveIsFree.
bool ReserveIsFreeHere() {
  std::FILE* file = std::fopen("/proc/sys/vm/overcommit_memory", "r");
  int mode = 0;
  if (file != nullptr) {
    if (std::fscanf(file, "%d", &mode) != 1) mode = 0;
    std::fclose(file);
  }
  return HeapReserveIsFree(std::getenv("MALLOC_PERTURB_"),
                           std::getenv("GLIBC_TUNABLES"), mode);
}

// Heap blocks allocated together and freed leave one free top chunk of
// their size, which later allocations are carved from; its whole 2 MiB
// pages are marked for huge pages.
void ReserveHugePageHeap() {
  if (!ReserveIsFreeHere()) return;
  constexpr std::size_t kBlockBytes = kMaxHeapBlockBytes / 2;
  std::vector<char*> blocks;
  for (std::size_t bytes = 0; bytes < kHugePageHeapBytes;
       bytes += kBlockBytes) {
    char* block = static_cast<char*>(std::malloc(kBlockBytes));
    if (block == nullptr) break;
    blocks.push_back(block);
  }
  if (blocks.empty()) return;
  std::uintptr_t low = UINTPTR_MAX, high = 0;
  for (char* block : blocks) {
    low = std::min(low, reinterpret_cast<std::uintptr_t>(block));
    high =
        std::max(high, reinterpret_cast<std::uintptr_t>(block) + kBlockBytes);
  }
  for (auto block = blocks.rbegin(); block != blocks.rend(); ++block) {
    std::free(*block);
  }
  constexpr std::uintptr_t kHugePage = std::uintptr_t{2} << 20;
  low = (low + kHugePage - 1) / kHugePage * kHugePage;
  high = high / kHugePage * kHugePage;
  // Advice only: where it fails (no huge pages, blocks not adjacent), pages
  // stay small.
  if (high > low) {
    madvise(reinterpret_cast<void*>(low), high - low, MADV_HUGEPAGE);
  }
}

}  // namespace
#endif

bool HeapReserveIsFree(const char* malloc_perturb, const char* glibc_tunables,
                       int overcommit_memory) {
  if (malloc_perturb != nullptr && std::atoi(malloc_perturb) != 0) {
    return false;
  }
  if (glibc_tunables != nullptr &&
      std::strstr(glibc_tunables, "glibc.malloc.perturb") != nullptr) {
    return false;
  }
  return overcommit_memory != 2;
}

bool RetainFreedMemory() {
#if defined(__GLIBC__)
  // Blocks above the mmap threshold are mapped apart and unmapped on free;
  // the heap's top is trimmed above the trim threshold.
  if (mallopt(M_MMAP_THRESHOLD, kMaxHeapBlockBytes) != 1 ||
      mallopt(M_TRIM_THRESHOLD, kRetainedBytes) != 1) {
    return false;
  }
  ReserveHugePageHeap();
  return true;
#else
  return false;
#endif
}

}  // namespace rff
