// The recovery decisions of the V4L2 driver, driven with made-up times and errnos: no
// device needed. Expected times are worked out by hand from the documented policy
// (first retry after backoff_initial, then doubling up to backoff_max).
#include "skyloc/drivers/stream_recovery.h"

#include <gtest/gtest.h>

#include <cerrno>

namespace skyloc::drivers {
namespace {

using std::chrono::milliseconds;
using State = StreamRecovery::State;

StreamRecoveryConfig Config(std::uint32_t max_failures = 0) {
  StreamRecoveryConfig c;
  c.stall_timeout = milliseconds(1000);
  c.backoff_initial = milliseconds(100);
  c.backoff_max = milliseconds(350);
  c.max_failures = max_failures;
  return c;
}

TEST(StreamRecovery, ClassifiesDeviceLossErrnos) {
  for (int e : {ENODEV, ENXIO, EIO, EPIPE, ESHUTDOWN, EBADF})
    EXPECT_TRUE(StreamRecovery::IsDeviceLoss(e)) << e;
  for (int e : {0, EAGAIN, EINTR, EINVAL, ENOMEM, EBUSY})
    EXPECT_FALSE(StreamRecovery::IsDeviceLoss(e)) << e;
}

TEST(StreamRecovery, StallIsDetectedOnlyAfterTheTimeoutWithoutFrames) {
  StreamRecovery r(Config());
  r.Started(milliseconds(0));
  EXPECT_FALSE(r.IsStalled(milliseconds(999)));
  EXPECT_TRUE(r.IsStalled(milliseconds(1000)));
  r.FrameArrived(milliseconds(900));
  EXPECT_FALSE(r.IsStalled(milliseconds(1899)));
  EXPECT_TRUE(r.IsStalled(milliseconds(1900)));
  EXPECT_EQ(r.stall_deadline(), milliseconds(1900));
}

TEST(StreamRecovery, BacksOffExponentiallyUpToTheMaximumThenRecovers) {
  StreamRecovery r(Config());
  r.Started(milliseconds(0));
  r.DeviceLost(milliseconds(500));
  EXPECT_EQ(r.state(), State::kBackingOff);
  EXPECT_FALSE(r.IsStalled(milliseconds(5000)));  // not streaming: no stall verdicts
  EXPECT_FALSE(r.ReopenDue(milliseconds(599)));
  EXPECT_TRUE(r.ReopenDue(milliseconds(600)));
  r.ReopenFailed(milliseconds(600));  // next after 200 ms
  EXPECT_EQ(r.next_attempt(), milliseconds(800));
  r.ReopenFailed(milliseconds(800));  // 400 > 350: capped
  EXPECT_EQ(r.next_attempt(), milliseconds(1150));
  r.ReopenFailed(milliseconds(1150));
  EXPECT_EQ(r.next_attempt(), milliseconds(1500));
  EXPECT_EQ(r.consecutive_failures(), 3u);
  EXPECT_EQ(r.state(), State::kBackingOff);  // max_failures 0: never gives up

  r.ReopenSucceeded(milliseconds(1500));
  EXPECT_EQ(r.state(), State::kStreaming);
  EXPECT_EQ(r.restarts(), 1u);
  EXPECT_EQ(r.consecutive_failures(), 0u);
  // The stall timer restarts with the stream.
  EXPECT_FALSE(r.IsStalled(milliseconds(2499)));
  EXPECT_TRUE(r.IsStalled(milliseconds(2500)));
  // A second loss starts again from the initial backoff.
  r.DeviceLost(milliseconds(3000));
  EXPECT_EQ(r.next_attempt(), milliseconds(3100));
}

TEST(StreamRecovery, GivesUpAfterMaxConsecutiveFailures) {
  StreamRecovery r(Config(2));
  r.Started(milliseconds(0));
  r.DeviceLost(milliseconds(0));
  r.ReopenFailed(milliseconds(100));
  EXPECT_EQ(r.state(), State::kBackingOff);
  r.ReopenFailed(milliseconds(300));
  EXPECT_EQ(r.state(), State::kFailed);
  EXPECT_FALSE(r.ReopenDue(milliseconds(100000)));
  // Failed is final: further events change nothing.
  r.DeviceLost(milliseconds(100000));
  r.ReopenSucceeded(milliseconds(100000));
  EXPECT_EQ(r.state(), State::kFailed);
  EXPECT_EQ(r.restarts(), 0u);
  // Only a new stream (the driver's Open/Start) resets it.
  r.Started(milliseconds(200000));
  EXPECT_EQ(r.state(), State::kStreaming);
}

TEST(StreamRecovery, EventsOutOfOrderAreIgnored) {
  StreamRecovery r(Config());
  r.Started(milliseconds(0));
  r.ReopenFailed(milliseconds(10));     // not backing off: ignored
  r.ReopenSucceeded(milliseconds(10));  // likewise: no phantom restart
  EXPECT_EQ(r.state(), State::kStreaming);
  EXPECT_EQ(r.consecutive_failures(), 0u);
  EXPECT_EQ(r.restarts(), 0u);
}

}  // namespace
}  // namespace skyloc::drivers
