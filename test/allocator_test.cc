#include "rff_ceres/allocator.h"

#include <cstdlib>
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
  {
    std::vector<char> buffer(kBytes, 1);
    EXPECT_EQ(mallinfo2().hblkhd, mapped_before);  // Not mapped apart.
  }
  EXPECT_GE(mallinfo2().fordblks, kBytes);  // Kept, free, in the heap.
}
#else
TEST(AllocatorTest, WithoutGlibcThereIsNothingToSet) {
  EXPECT_FALSE(RetainFreedMemory());
}
#endif

}  // namespace
}  // namespace rff
