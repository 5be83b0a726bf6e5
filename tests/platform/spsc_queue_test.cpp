// The hand-over queue between libcamera's completion thread and the pipeline thread.
#include "skyloc/platform/spsc_queue.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <thread>

#include "support/emulator.h"

namespace skyloc {
namespace {

TEST(SpscQueue, IsFifoAndReportsFullAndEmpty) {
  SpscQueue<int, 4> q;
  int v = 0;
  EXPECT_FALSE(q.TryPop(&v));
  for (int i = 0; i < 4; ++i)
    EXPECT_TRUE(q.TryPush(i));
  EXPECT_FALSE(q.TryPush(99));  // full: refused, nothing overwritten
  EXPECT_EQ(q.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(q.TryPop(&v));
    EXPECT_EQ(v, i);
  }
  EXPECT_FALSE(q.TryPop(&v));
  // Wrap around the index many times.
  for (int i = 0; i < 1000; ++i) {
    ASSERT_TRUE(q.TryPush(i));
    ASSERT_TRUE(q.TryPop(&v));
    ASSERT_EQ(v, i);
  }
}

TEST(SpscQueue, TwoThreadsLoseAndReorderNothing) {
  // The producer pushes 0..N-1 (retrying when full); the consumer must see exactly that
  // sequence. Under TSan/ASan builds this also exercises the memory ordering. Under
  // qemu-user, where every yield of a spinning thread costs a host context switch, 20,000:
  // still more than a thousand laps of the 16 slots.
  const std::uint64_t kCount = skyloc::testing::UnderUserModeEmulator() ? 20'000 : 200'000;
  SpscQueue<std::uint64_t, 16> q;
  std::thread producer([&q, kCount] {
    for (std::uint64_t i = 0; i < kCount;) {
      if (q.TryPush(i))
        ++i;
      else
        std::this_thread::yield();
    }
  });
  std::uint64_t expected = 0;
  std::uint64_t mismatches = 0;
  while (expected < kCount) {
    std::uint64_t v = 0;
    if (q.TryPop(&v)) {
      mismatches += v != expected;
      ++expected;
    } else {
      std::this_thread::yield();
    }
  }
  producer.join();
  EXPECT_EQ(mismatches, 0u);
  EXPECT_EQ(q.size(), 0u);
}

}  // namespace
}  // namespace skyloc
