// The allocation counter must fail a loop that allocates and pass one that does not;
// otherwise the "no allocation after start-up" tests built on it prove nothing.
#include "skyloc/platform/alloc_counter.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "skyloc/platform/fixed_array.h"
#include "skyloc/platform/ring_buffer.h"

namespace skyloc {
namespace {

// Opaque to the optimiser, so allocations in the loops below cannot be elided.
template <typename T>
void Escape(T* p) {
  asm volatile("" : : "g"(p) : "memory");
}

TEST(AllocationCounter, IsLinked) {
  EXPECT_TRUE(AllocationCounterActive());
}

TEST(AllocationCounter, CountsNewInALoop) {
  AllocationScope scope;
  for (int i = 0; i < 100; ++i) {
    auto p = std::make_unique<int>(i);
    Escape(p.get());
  }
  EXPECT_EQ(scope.allocations(), 100u);
  EXPECT_EQ(scope.bytes(), 100u * sizeof(int));
}

TEST(AllocationCounter, CountsHiddenVectorGrowth) {
  AllocationScope scope;
  std::vector<int> v;
  for (int i = 0; i < 100; ++i)
    v.push_back(i);
  Escape(v.data());
  EXPECT_GT(scope.allocations(), 0u);
}

TEST(AllocationCounter, CountsStringConcatenation) {
  AllocationScope scope;
  std::string s;
  for (int i = 0; i < 50; ++i)
    s += "frame number " + std::to_string(i);
  Escape(s.data());
  EXPECT_GT(scope.allocations(), 0u);
}

#if !defined(SKYLOC_SANITIZED)
TEST(AllocationCounter, CountsMallocFromC) {
  AllocationScope scope;
  void* p = std::malloc(64);
  Escape(p);
  std::free(p);
  EXPECT_EQ(scope.allocations(), 1u);
}
#endif

TEST(AllocationCounter, ZeroForAFixedMemoryLoop) {
  // Start-up: everything allocated once.
  FixedArray<float> storage;
  ASSERT_TRUE(storage.Allocate(64).ok());
  RingBuffer<float> ring(storage.span());
  FixedArray<float> scratch;
  ASSERT_TRUE(scratch.Allocate(256).ok());

  AllocationScope scope;
  float sum = 0;
  for (int frame = 0; frame < 10000; ++frame) {
    for (std::size_t i = 0; i < scratch.size(); ++i)
      scratch[i] = static_cast<float>(i) + static_cast<float>(frame);
    ring.PushOverwrite(scratch[static_cast<std::size_t>(frame) % scratch.size()]);
    sum += ring.FromNewest(0);
  }
  Escape(&sum);
  EXPECT_EQ(scope.allocations(), 0u);
}

}  // namespace
}  // namespace skyloc
