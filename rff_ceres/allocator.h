// The C library's allocator set for a solver's working set. A solve frees
// and allocates the same large buffers round after round (the system's
// envelope, its factor, the Jacobian: megabytes each); by default glibc
// hands such blocks back to the system on free and faults every page in
// again on the next allocation, about a tenth of a Plaza 1 solve.
#ifndef RFF_CERES_ALLOCATOR_H_
#define RFF_CERES_ALLOCATOR_H_

namespace rff {

// Keeps up to kRetainedBytes of freed memory in the process for reuse, and
// serves blocks of up to kMaxHeapBlockBytes (glibc's largest) from it.
// A process-wide setting: for the command-line tools, called once at the
// start of main. False where the C library has no such setting.
constexpr int kRetainedBytes = 1 << 30;
constexpr int kMaxHeapBlockBytes = 1 << 25;
bool RetainFreedMemory();

}  // namespace rff

#endif  // RFF_CERES_ALLOCATOR_H_
