// The C library's allocator set for a solver's working set. A solve frees
// and allocates the same large buffers round after round (the system's
// envelope, its factor, the Jacobian: megabytes each); by default glibc
// hands such blocks back to the system on free and faults every page in
// again on the next allocation, about a tenth of a Plaza 1 solve. Pages
// touched for the first time still fault one by one, 4 KiB each: on a
// virtual machine that is another tenth, which transparent huge pages
// (2 MiB per fault) remove.
#ifndef RFF_CERES_ALLOCATOR_H_
#define RFF_CERES_ALLOCATOR_H_

#include <cstddef>

namespace rff {

// Keeps up to kRetainedBytes of freed memory in the process for reuse, and
// serves blocks of up to kMaxHeapBlockBytes (glibc's largest) from it.
// Then grows the heap by kHugePageHeapBytes of address space (nothing is
// touched, so nothing is resident) and asks the kernel for transparent huge
// pages there (madvise; where the kernel has them off, nothing changes).
// A process-wide setting: for the command-line tools, called once at the
// start of main. False where the C library has no such setting.
constexpr int kRetainedBytes = 1 << 30;
constexpr int kMaxHeapBlockBytes = 1 << 25;
constexpr std::size_t kHugePageHeapBytes = std::size_t{256} << 20;
bool RetainFreedMemory();

}  // namespace rff

#endif  // RFF_CERES_ALLOCATOR_H_
