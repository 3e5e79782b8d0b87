#include "rff_ceres/allocator.h"

#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "gtest/gtest.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace rff {
namespace {

#if defined(__GLIBC__)
// A freed 16 MB buffer stays in the heap for the next one (by default glibc
// maps it apart and unmaps it on free).
TEST(AllocatorTest, FreedLargeBuffersStayForReuse) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer replaces the allocator";
#endif
  ASSERT_TRUE(RetainFreedMemory());
  constexpr std::size_t kBytes = std::size_t{16} << 20;
  const std::size_t mapped_before = mallinfo2().hblkhd;
  std::size_t free_while_used;
  {
    std::vector<char> buffer(kBytes, 1);
    EXPECT_EQ(mallinfo2().hblkhd, mapped_before);  // Not mapped apart.
    free_while_used = mallinfo2().fordblks;
  }
  // Kept, free, in the heap.
  EXPECT_GE(mallinfo2().fordblks, free_while_used + kBytes);
}

// Whether the kernel gives transparent huge pages where madvise asks.
bool HugePagesOnAdvice() {
  std::ifstream file("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string modes;
  std::getline(file, modes);
  return modes.find("[always]") != std::string::npos ||
         modes.find("[madvise]") != std::string::npos;
}

// Bytes of the mappings around `address` that /proc/self/smaps marks for
// huge pages ("hg" in VmFlags), or -1 when no mapping holds it.
std::int64_t AdvisedBytesAt(const void* address) {
  std::ifstream smaps("/proc/self/smaps");
  const auto target = reinterpret_cast<std::uintptr_t>(address);
  std::string line;
  bool inside = false;
  std::int64_t size = 0;
  while (std::getline(smaps, line)) {
    std::uintptr_t begin, end;
    char dash;
    std::istringstream head(line);
    if (line.find("VmFlags:") == 0) {
      if (inside) return line.find(" hg") != std::string::npos ? size : 0;
    } else if (head >> std::hex >> begin >> dash >> end && dash == '-' &&
               line.find(':') > line.find(' ')) {
      inside = begin <= target && target < end;
      size = static_cast<std::int64_t>(end - begin);
    }
  }
  return -1;
}

// The heap's reserve is free for reuse and, where the kernel has them,
// marked for huge pages: a large buffer allocated after lands there.
TEST(AllocatorTest, TheHeapIsReservedWithHugePages) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer replaces the allocator";
#endif
  ASSERT_TRUE(RetainFreedMemory());
  std::ifstream overcommit("/proc/sys/vm/overcommit_memory");
  int mode = 0;
  overcommit >> mode;
  if (!HeapReserveIsFree(std::getenv("MALLOC_PERTURB_"),
                         std::getenv("GLIBC_TUNABLES"), mode)) {
    GTEST_SKIP() << "the reserve is not free here: nothing is reserved";
  }
  EXPECT_GE(mallinfo2().fordblks,
            kHugePageHeapBytes - (kHugePageHeapBytes >> 3));
  if (!HugePagesOnAdvice()) {
    GTEST_SKIP() << "transparent huge pages are off on this machine";
  }
  std::vector<char> buffer(std::size_t{64} << 20);
  const void* middle = buffer.data() + buffer.size() / 2;
  EXPECT_GE(AdvisedBytesAt(middle), std::int64_t{64} << 20);
}
#endif

// glibc's perturb would write the reserve in full; strict overcommit would
// charge it.
TEST(AllocatorTest, TheReserveIsMadeOnlyWhereItIsFree) {
  EXPECT_TRUE(HeapReserveIsFree(nullptr, nullptr, 0));
  EXPECT_TRUE(HeapReserveIsFree("0", "glibc.malloc.hugetlb=1", 1));
  EXPECT_FALSE(HeapReserveIsFree("165", nullptr, 0));
  EXPECT_FALSE(HeapReserveIsFree(nullptr, "glibc.malloc.perturb=165", 0));
  EXPECT_FALSE(HeapReserveIsFree(nullptr, nullptr, 2));
}

#if !defined(__GLIBC__)
TEST(AllocatorTest, WithoutGlibcThereIsNothingToSet) {
  EXPECT_FALSE(RetainFreedMemory());
}
#endif

}  // namespace
}  // namespace rff
