#include "skyloc/platform/clock.h"

#include <gtest/gtest.h>
#include <time.h>

namespace skyloc {
namespace {

TEST(MonotonicClock, AgreesWithClockGettimeAndNeverGoesBack) {
  MonotonicClock clock;
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  const Nanoseconds before{static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec};
  Nanoseconds last = clock.Now();
  EXPECT_GE(last, before);
  for (int i = 0; i < 1000; ++i) {
    const Nanoseconds now = clock.Now();
    EXPECT_GE(now, last);
    last = now;
  }
}

TEST(ManualClock, MovesOnlyForwardWhenTold) {
  ManualClock clock(Nanoseconds{100});
  EXPECT_EQ(clock.Now(), Nanoseconds{100});
  clock.Advance(Nanoseconds{50});
  EXPECT_EQ(clock.Now(), Nanoseconds{150});
  clock.Advance(Nanoseconds{-10});
  clock.Set(Nanoseconds{20});
  EXPECT_EQ(clock.Now(), Nanoseconds{150});
}

}  // namespace
}  // namespace skyloc
