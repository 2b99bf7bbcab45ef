// keep_freed_memory: a block of 64 MiB comes from the heap rather than from its own mapping, and once freed
// it stays in the process for the next allocation (no page faults to fill it again). It sets the process's
// allocator for the rest of this test program too, as it does for snh.
#include <gtest/gtest.h>

#include <malloc.h>

#include <cstdlib>
#include <cstring>

#include "snh/math/keep_memory.hpp"

namespace snh {
namespace {

TEST(KeepMemory, ABigBlockComesFromTheHeapAndStaysThereWhenFreed) {
  constexpr std::size_t kBytes = std::size_t{64} << 20;
  keep_freed_memory();
  const struct mallinfo2 before = mallinfo2();
  void* block = std::malloc(kBytes);
  ASSERT_NE(block, nullptr);
  std::memset(block, 1, kBytes);
  const struct mallinfo2 held = mallinfo2();
  EXPECT_LT(held.hblkhd, before.hblkhd + kBytes) << "not a mapping of its own";
  EXPECT_GE(held.uordblks, before.uordblks + kBytes) << "in the heap";
  std::free(block);
  const struct mallinfo2 freed = mallinfo2();
  EXPECT_GE(freed.fordblks, kBytes) << "kept in the heap, free for the next allocation";
}

}  // namespace
}  // namespace snh
