// The real V4L2 driver code over a scripted device (V4l2Io): format negotiation, the
// requeue cycle, drops, corrupt frames, and the recovery state machine in action —
// unplug, failed reopens with backoff, stall restart, giving up — with no hardware and
// no wall time (the fake's clock moves only when the driver polls or sleeps).
#include <gtest/gtest.h>

#if SKYLOC_WITH_V4L2

#include <cstring>
#include <string>

#include "fake_v4l2_device.h"
#include "skyloc/drivers/v4l2_camera.h"
#include "skyloc/platform/alloc_counter.h"

namespace skyloc::drivers {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;
using testing::FakeV4l2Device;

class V4l2FakeDeviceTest : public ::testing::Test {
 protected:
  static V4l2CameraConfig Config() {
    V4l2CameraConfig c;
    std::strcpy(c.device, "/dev/video0");
    c.capture.width = 320;
    c.capture.height = 240;
    c.capture.fps = 25;
    c.recovery.stall_timeout = seconds(2);
    c.recovery.backoff_initial = milliseconds(100);
    c.recovery.backoff_max = milliseconds(400);
    return c;
  }
  void OpenAndStart() {
    const Status open = camera_.Open();
    ASSERT_TRUE(open.ok()) << open.message();
    const Status start = camera_.Start();
    ASSERT_TRUE(start.ok()) << start.message();
  }
  // Captures one frame and checks its pixels carry its device sequence number.
  std::uint64_t Next(Nanoseconds timeout = seconds(1)) {
    Result<Frame> f = camera_.Capture(timeout);
    EXPECT_TRUE(f.ok()) << f.status().message();
    if (!f.ok())
      return ~0ull;
    return f->sequence;
  }

  FakeV4l2Device device_;
  V4l2Camera camera_{Config(), &device_};
};

TEST_F(V4l2FakeDeviceTest, NegotiatesGreyFirstAndReportsWhatTheDriverChose) {
  OpenAndStart();
  EXPECT_EQ(camera_.info().format, dsp::PixelFormat::kGrey8);  // offered second, preferred
  EXPECT_EQ(camera_.info().width, 64);                         // adjusted by the driver
  EXPECT_EQ(camera_.info().height, 48);
  EXPECT_DOUBLE_EQ(camera_.fps(), 25.0);
  EXPECT_STREQ(camera_.device_path(), "/dev/video0");
  Result<Frame> f = camera_.Capture(seconds(1));
  ASSERT_TRUE(f.ok()) << f.status().message();
  EXPECT_EQ(f->image.stride, 72u);  // bytesperline, with the driver's padding
  for (int y = 0; y < f->image.height; ++y)
    for (int x = 0; x < f->image.width; ++x)
      ASSERT_EQ(f->image.Row(y)[x], static_cast<std::uint8_t>(x + y)) << x << "," << y;
  EXPECT_EQ(f->timestamp, seconds(10) + milliseconds(40));  // the buffer's own timestamp
}

TEST_F(V4l2FakeDeviceTest, FindsTheDeviceByDriverAndCardName) {
  device_.node = "/dev/video5";
  V4l2CameraConfig c = Config();
  std::strcpy(c.device, "fake:Fake Cam");
  V4l2Camera by_name(c, &device_);
  const Status s = by_name.Open();
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_STREQ(by_name.device_path(), "/dev/video5");
  by_name.Close();
  std::strcpy(c.device, "fake:Other Cam");
  V4l2Camera wrong(c, &device_);
  const Status missing = wrong.Open();
  EXPECT_EQ(missing.code(), StatusCode::kNotFound);
  EXPECT_NE(std::string(missing.message()).find("Other Cam"), std::string::npos);
}

TEST_F(V4l2FakeDeviceTest, UnsupportedFormatsAreListedInTheError) {
  device_.formats = {V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_NV12};
  const Status s = camera_.Open();
  EXPECT_EQ(s.code(), StatusCode::kUnimplemented);
  EXPECT_NE(std::string(s.message()).find("[MJPG NV12]"), std::string::npos) << s.message();
  EXPECT_EQ(camera_.state(), Camera::State::kClosed);
}

TEST_F(V4l2FakeDeviceTest, SequenceGapsCountAsDrops) {
  OpenAndStart();
  EXPECT_EQ(Next(), 0u);
  device_.skip_sequences = 3;
  EXPECT_EQ(Next(), 4u);
  EXPECT_EQ(Next(), 5u);
  EXPECT_EQ(camera_.counters().dropped, 3u);
}

// The Camera contract is a strictly increasing frame number (the recorder and the drop
// counter rely on it), whatever the driver stamps: vivid gave two frames the same sequence
// number in a starved guest, and the compliance suite failed on it.
TEST_F(V4l2FakeDeviceTest, ARepeatedDriverSequenceStillGivesIncreasingFrameNumbers) {
  OpenAndStart();
  EXPECT_EQ(Next(), 0u);
  EXPECT_EQ(Next(), 1u);
  device_.repeat_last_sequence = true;  // the driver's 1 again
  EXPECT_EQ(Next(), 2u);
  EXPECT_EQ(Next(), 3u);       // the driver's 2: the numbering goes on from ours
  device_.skip_sequences = 2;  // the driver's 5: two frames lost
  EXPECT_EQ(Next(), 6u);
  EXPECT_EQ(camera_.counters().dropped, 2u);
}

TEST_F(V4l2FakeDeviceTest, CorruptFramesAreDataLossAndTheStreamGoesOn) {
  OpenAndStart();
  EXPECT_EQ(Next(), 0u);
  device_.next_frame_error = true;
  EXPECT_EQ(camera_.Capture(seconds(1)).status().code(), StatusCode::kDataLoss);
  device_.next_frame_short = true;
  EXPECT_EQ(camera_.Capture(seconds(1)).status().code(), StatusCode::kDataLoss);
  EXPECT_EQ(Next(), 3u);  // the bad frames' buffers were requeued
  EXPECT_EQ(camera_.counters().dropped, 0u);
}

TEST_F(V4l2FakeDeviceTest, ZeroTimeoutIsDeadlineExceeded) {
  OpenAndStart();
  EXPECT_EQ(camera_.Capture(Nanoseconds(0)).status().code(), StatusCode::kDeadlineExceeded);
  EXPECT_EQ(Next(), 0u);
}

TEST_F(V4l2FakeDeviceTest, SpuriousWakeupsStillEndAtTheDeadline) {
  OpenAndStart();
  EXPECT_EQ(Next(), 0u);
  device_.spurious_wakeups = true;
  const Nanoseconds before = device_.Now();
  EXPECT_EQ(camera_.Capture(milliseconds(100)).status().code(), StatusCode::kDeadlineExceeded);
  EXPECT_EQ(device_.Now() - before, milliseconds(100));
  device_.spurious_wakeups = false;
  EXPECT_EQ(Next(), 1u);
}

TEST_F(V4l2FakeDeviceTest, UnplugThenReplugIsRecoveredWithBackoff) {
  OpenAndStart();
  EXPECT_EQ(Next(), 0u);
  EXPECT_EQ(Next(), 1u);
  device_.unplugged = true;
  Result<Frame> lost = camera_.Capture(seconds(1));
  EXPECT_EQ(lost.status().code(), StatusCode::kUnavailable);
  EXPECT_NE(std::string(lost.status().message()).find("device lost"), std::string::npos)
      << lost.status().message();
  EXPECT_EQ(camera_.recovery().state(), StreamRecovery::State::kBackingOff);
  // Still unplugged: reopen attempts at +100, +300 (200 later), +700 (400, the cap),
  // +1100 ms: within a 1.2 s Capture() all four fail, and it reports the device gone.
  const Nanoseconds before = device_.Now();
  EXPECT_EQ(camera_.Capture(milliseconds(1200)).status().code(), StatusCode::kUnavailable);
  EXPECT_EQ(camera_.recovery().consecutive_failures(), 4u);
  EXPECT_EQ(device_.Now() - before, milliseconds(1200));  // slept until the deadline
  EXPECT_EQ(camera_.counters().restarts, 0u);
  // Replugged: the next attempt (at +1500 ms) succeeds and frames continue in sequence.
  device_.unplugged = false;
  const int opens = device_.opens;
  EXPECT_EQ(Next(seconds(1)), 2u);
  EXPECT_EQ(device_.opens, opens + 1);
  EXPECT_EQ(camera_.counters().restarts, 1u);
  EXPECT_EQ(camera_.recovery().state(), StreamRecovery::State::kStreaming);
  EXPECT_EQ(Next(), 3u);
  EXPECT_EQ(camera_.counters().dropped, 0u);
}

TEST_F(V4l2FakeDeviceTest, ADeviceThatComesBackDifferentIsNotAccepted) {
  OpenAndStart();
  EXPECT_EQ(Next(), 0u);
  device_.unplugged = true;
  EXPECT_EQ(camera_.Capture(seconds(1)).status().code(), StatusCode::kUnavailable);
  device_.unplugged = false;
  device_.max_width = 32;  // another camera on the same port
  Result<Frame> refused = camera_.Capture(milliseconds(150));
  EXPECT_EQ(refused.status().code(), StatusCode::kUnavailable);
  // The operator learns why the reopen did not count.
  EXPECT_NE(std::string(refused.status().message()).find("came back as 32x48"), std::string::npos)
      << refused.status().message();
  EXPECT_EQ(camera_.recovery().consecutive_failures(), 1u);
  EXPECT_EQ(camera_.info().width, 64);  // still what the pipeline was built for
  device_.max_width = 64;               // the right camera again
  EXPECT_EQ(Next(), 1u);
  EXPECT_EQ(camera_.counters().restarts, 1u);
}

TEST_F(V4l2FakeDeviceTest, FaultsAndRecoveryDoNotAllocate) {
  // The pipeline keeps calling Capture() through an outage: losing the device, backing
  // off, reopening (open, format, mmap) and resuming must not touch the heap either.
  ASSERT_TRUE(AllocationCounterActive());
  OpenAndStart();
  EXPECT_EQ(Next(), 0u);
  AllocationScope scope;
  device_.unplugged = true;
  for (int i = 0; i < 3; ++i)
    EXPECT_EQ(camera_.Capture(milliseconds(300)).status().code(), StatusCode::kUnavailable);
  device_.unplugged = false;
  EXPECT_EQ(Next(), 1u);
  device_.next_frame_error = true;
  EXPECT_EQ(camera_.Capture(seconds(1)).status().code(), StatusCode::kDataLoss);
  EXPECT_EQ(Next(), 3u);
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(camera_.counters().restarts, 1u);
}

TEST_F(V4l2FakeDeviceTest, StalledStreamIsRestarted) {
  OpenAndStart();
  EXPECT_EQ(Next(), 0u);
  device_.stalled = true;
  // 500 ms timeouts: three plain timeouts, then 2 s without frames is a stall.
  for (int i = 0; i < 3; ++i)
    EXPECT_EQ(camera_.Capture(milliseconds(500)).status().code(), StatusCode::kDeadlineExceeded);
  Result<Frame> stall = camera_.Capture(milliseconds(500));
  EXPECT_EQ(stall.status().code(), StatusCode::kUnavailable);
  EXPECT_NE(std::string(stall.status().message()).find("stalled"), std::string::npos);
  device_.stalled = false;
  EXPECT_EQ(Next(), 1u);
  EXPECT_EQ(camera_.counters().restarts, 1u);
  EXPECT_EQ(device_.streamons, 2);
}

TEST_F(V4l2FakeDeviceTest, GivesUpAfterMaxFailuresAndSaysWhatToCheck) {
  V4l2CameraConfig c = Config();
  c.recovery.max_failures = 3;
  V4l2Camera camera(c, &device_);
  ASSERT_TRUE(camera.Open().ok());
  ASSERT_TRUE(camera.Start().ok());
  ASSERT_TRUE(camera.Capture(seconds(1)).ok());
  device_.unplugged = true;
  for (int i = 0; i < 10 && camera.recovery().state() != StreamRecovery::State::kFailed; ++i)
    EXPECT_EQ(camera.Capture(seconds(1)).status().code(), StatusCode::kUnavailable);
  EXPECT_EQ(camera.recovery().state(), StreamRecovery::State::kFailed);
  device_.unplugged = false;  // too late: the driver gave up
  Result<Frame> f = camera.Capture(seconds(1));
  EXPECT_EQ(f.status().code(), StatusCode::kUnavailable);
  EXPECT_NE(std::string(f.status().message()).find("gave up"), std::string::npos);
  // A fresh Stop/Start (the operator's restart) streams again.
  camera.Stop();
  ASSERT_TRUE(camera.Start().ok());
  EXPECT_TRUE(camera.Capture(seconds(1)).ok());
}

TEST_F(V4l2FakeDeviceTest, StopAndStartContinueTheSequence) {
  OpenAndStart();
  EXPECT_EQ(Next(), 0u);
  EXPECT_EQ(Next(), 1u);
  camera_.Stop();
  ASSERT_TRUE(camera_.Start().ok());
  EXPECT_EQ(Next(), 2u);  // the device counts from 0 again; the driver does not
  EXPECT_EQ(camera_.counters().dropped, 0u);
}

}  // namespace
}  // namespace skyloc::drivers

#endif  // SKYLOC_WITH_V4L2
