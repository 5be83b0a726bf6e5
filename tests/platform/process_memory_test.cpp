// The RSS reader sees memory the process touches.
#include "skyloc/platform/process_memory.h"

#include <gtest/gtest.h>

#include <cstring>
#include <memory>

#include "skyloc/platform/alloc_counter.h"

namespace skyloc {
namespace {

TEST(ProcessMemory, GrowsWhenMemoryIsTouched) {
  Result<std::size_t> before = ResidentSetBytes();
  ASSERT_TRUE(before.ok()) << before.status().message();
  EXPECT_GT(*before, 0u);
  constexpr std::size_t kBytes = 64u << 20;
  std::unique_ptr<char[]> block(new char[kBytes]);
  std::memset(block.get(), 1, kBytes);
  asm volatile("" : : "g"(block.get()) : "memory");
  Result<std::size_t> after = ResidentSetBytes();
  ASSERT_TRUE(after.ok());
  EXPECT_GE(*after, *before + kBytes * 9 / 10);
}

TEST(ProcessMemory, ReadingDoesNotAllocate) {
  AllocationScope scope;
  for (int i = 0; i < 10; ++i)
    ASSERT_TRUE(ResidentSetBytes().ok());
  EXPECT_EQ(scope.allocations(), 0u);
}

}  // namespace
}  // namespace skyloc
