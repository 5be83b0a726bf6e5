#include "skyloc/platform/ring_buffer.h"

#include <gtest/gtest.h>

#include <array>
#include <deque>
#include <random>

namespace skyloc {
namespace {

TEST(RingBuffer, TryPushReportsFull) {
  std::array<int, 3> storage{};
  RingBuffer<int> ring(storage);
  EXPECT_TRUE(ring.empty());
  EXPECT_TRUE(ring.TryPush(1));
  EXPECT_TRUE(ring.TryPush(2));
  EXPECT_TRUE(ring.TryPush(3));
  EXPECT_TRUE(ring.full());
  EXPECT_FALSE(ring.TryPush(4));
  EXPECT_EQ(ring.size(), 3u);
  EXPECT_EQ(ring[0], 1);
  EXPECT_EQ(ring[2], 3);
  EXPECT_EQ(ring.overwritten(), 0u);
}

TEST(RingBuffer, PushOverwriteDropsOldestAndCounts) {
  std::array<int, 3> storage{};
  RingBuffer<int> ring(storage);
  for (int i = 1; i <= 5; ++i)
    ring.PushOverwrite(i);
  EXPECT_EQ(ring.size(), 3u);
  EXPECT_EQ(ring.overwritten(), 2u);
  EXPECT_EQ(ring[0], 3);
  EXPECT_EQ(ring[1], 4);
  EXPECT_EQ(ring[2], 5);
  EXPECT_EQ(ring.FromNewest(0), 5);
  EXPECT_EQ(ring.FromNewest(2), 3);
}

TEST(RingBuffer, ZeroCapacityRefusesPush) {
  RingBuffer<int> ring;
  EXPECT_FALSE(ring.TryPush(1));
  EXPECT_TRUE(ring.empty());
}

TEST(RingBuffer, MatchesDequeModelUnderRandomOperations) {
  // Reference: std::deque bounded by hand. 10k random operations must agree exactly.
  std::array<int, 7> storage{};
  RingBuffer<int> ring(storage);
  std::deque<int> model;
  std::uint64_t model_overwritten = 0;
  std::mt19937 rng(1234);
  for (int step = 0; step < 10000; ++step) {
    const int op = static_cast<int>(rng() % 4);
    if (op == 0) {
      const bool pushed = ring.TryPush(step);
      EXPECT_EQ(pushed, model.size() < storage.size());
      if (model.size() < storage.size())
        model.push_back(step);
    } else if (op == 1) {
      ring.PushOverwrite(step);
      if (model.size() == storage.size()) {
        model.pop_front();
        ++model_overwritten;
      }
      model.push_back(step);
    } else if (op == 2) {
      EXPECT_EQ(ring.PopOldest(), !model.empty());
      if (!model.empty())
        model.pop_front();
    } else {
      ASSERT_EQ(ring.size(), model.size());
      for (std::size_t i = 0; i < model.size(); ++i)
        ASSERT_EQ(ring[i], model[i]);
    }
  }
  EXPECT_EQ(ring.overwritten(), model_overwritten);
}

}  // namespace
}  // namespace skyloc
