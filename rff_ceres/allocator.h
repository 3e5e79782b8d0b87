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
// Only where that is free (HeapReserveIsFree).
// A process-wide setting: for the command-line tools, called once at the
// start of main. False where the C library has no such setting.
constexpr int kRetainedBytes = 1 << 30;
constexpr int kMaxHeapBlockBytes = 1 << 25;
constexpr std::size_t kHugePageHeapBytes = std::size_t{256} << 20;
bool RetainFreedMemory();

// Whether the reserve costs nothing: not where glibc fills memory on every
// malloc and free (MALLOC_PERTURB_ non-zero, glibc.malloc.perturb in
// GLIBC_TUNABLES: the reserve would be written in full), nor under strict
// overcommit (vm.overcommit_memory 2: it would hold its size of commit
// charge). Null for an unset variable.
bool HeapReserveIsFree(const char* malloc_perturb, const char* glibc_tunables,
                       int overcommit_memory);

}  // namespace rff

#endif  // RFF_CERES_ALLOCATOR_H_
