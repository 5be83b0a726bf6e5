// Fault injection in the simulated camera, and its frames against the source's own
// per-pixel reference.
#include "skyloc/drivers/simulated_camera.h"

#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <string>

#include "skyloc/drivers/frame_source.h"
#include "skyloc/platform/alloc_counter.h"
#include "skyloc/platform/clock.h"

namespace skyloc::drivers {
namespace {

using std::chrono::milliseconds;

class SimulatedCameraTest : public ::testing::Test {
 protected:
  SimulatedCameraTest() : camera_(Config(), &source_, &clock_) {}
  static SimulatedCameraConfig Config() {
    SimulatedCameraConfig c;
    c.width = 40;
    c.height = 30;
    c.frame_interval = milliseconds(50);
    return c;
  }
  void OpenAndStart() {
    ASSERT_TRUE(camera_.Open().ok());
    ASSERT_TRUE(camera_.Start().ok());
  }
  std::uint64_t NextSequence() {
    Result<Frame> f = camera_.Capture(milliseconds(100));
    EXPECT_TRUE(f.ok()) << f.status().message();
    return f.ok() ? f->sequence : ~0ull;
  }

  SyntheticSkySource source_;
  ManualClock clock_{milliseconds(1000)};
  SimulatedCamera camera_;
};

TEST_F(SimulatedCameraTest, FramesMatchTheSourceAndCarryItsPose) {
  OpenAndStart();
  for (std::uint64_t i = 0; i < 3; ++i) {
    Result<Frame> f = camera_.Capture(milliseconds(100));
    ASSERT_TRUE(f.ok());
    EXPECT_EQ(f->sequence, i);
    for (int y = 0; y < f->image.height; ++y)
      for (int x = 0; x < f->image.width; ++x)
        ASSERT_EQ(f->image.Row(y)[x], source_.GreyAt(i, x, y, 40, 30)) << x << "," << y;
    ASSERT_TRUE(f->pose.has_value());
    EXPECT_DOUBLE_EQ(f->pose->x_m, 0.1 * static_cast<double>(i));
    EXPECT_DOUBLE_EQ(f->pose->yaw_deg, static_cast<double>(i));
  }
}

TEST_F(SimulatedCameraTest, TimestampsFollowTheInjectedClock) {
  OpenAndStart();
  Result<Frame> a = camera_.Capture(milliseconds(100));
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(a->timestamp, milliseconds(1000));
  // The clock did not move: the next frame is one interval later.
  Result<Frame> b = camera_.Capture(milliseconds(100));
  ASSERT_TRUE(b.ok());
  EXPECT_EQ(b->timestamp, milliseconds(1050));
  // The clock ran ahead: the frame is stamped with the clock.
  clock_.Advance(milliseconds(500));
  Result<Frame> c = camera_.Capture(milliseconds(100));
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->timestamp, milliseconds(1500));
}

TEST_F(SimulatedCameraTest, DroppedFramesLeaveASequenceGapAndAreCounted) {
  ASSERT_TRUE(camera_.InjectFault({CameraFault::Kind::kDrop, 2, 3}).ok());
  OpenAndStart();
  EXPECT_EQ(NextSequence(), 0u);
  EXPECT_EQ(NextSequence(), 1u);
  EXPECT_EQ(NextSequence(), 5u);  // 2, 3, 4 dropped
  EXPECT_EQ(NextSequence(), 6u);
  EXPECT_EQ(camera_.counters().dropped, 3u);
  EXPECT_EQ(camera_.counters().errors, 0u);
}

TEST_F(SimulatedCameraTest, StallTimesOutThenResumes) {
  ASSERT_TRUE(camera_.InjectFault({CameraFault::Kind::kStall, 1, 2}).ok());
  OpenAndStart();
  EXPECT_EQ(NextSequence(), 0u);
  for (int i = 0; i < 2; ++i) {
    Result<Frame> f = camera_.Capture(milliseconds(100));
    EXPECT_EQ(f.status().code(), StatusCode::kDeadlineExceeded);
  }
  EXPECT_EQ(NextSequence(), 1u);  // nothing lost, only late
  // A wait that ends before a frame is not an error of the camera: the caller chose the
  // timeout (the frame loop wakes to blink the status line), and it tells a stall itself.
  EXPECT_EQ(camera_.counters().errors, 0u);
  EXPECT_EQ(camera_.counters().restarts, 0u);
}

TEST_F(SimulatedCameraTest, DisconnectIsUnavailableThenRecoversAsARestart) {
  ASSERT_TRUE(camera_.InjectFault({CameraFault::Kind::kDisconnect, 2, 3}).ok());
  OpenAndStart();
  EXPECT_EQ(NextSequence(), 0u);
  EXPECT_EQ(NextSequence(), 1u);
  for (int i = 0; i < 3; ++i) {
    Result<Frame> f = camera_.Capture(milliseconds(100));
    EXPECT_EQ(f.status().code(), StatusCode::kUnavailable);
    EXPECT_EQ(camera_.counters().restarts, 0u);
  }
  EXPECT_EQ(NextSequence(), 2u);
  EXPECT_EQ(camera_.counters().restarts, 1u);
  EXPECT_EQ(camera_.counters().errors, 3u);
  EXPECT_EQ(camera_.state(), Camera::State::kStreaming);
}

TEST_F(SimulatedCameraTest, CorruptFrameSizeIsDataLossAndTheNextFrameIsFine) {
  ASSERT_TRUE(camera_.InjectFault({CameraFault::Kind::kCorruptSize, 1, 1}).ok());
  OpenAndStart();
  EXPECT_EQ(NextSequence(), 0u);
  Result<Frame> bad = camera_.Capture(milliseconds(100));
  EXPECT_EQ(bad.status().code(), StatusCode::kDataLoss);
  EXPECT_EQ(NextSequence(), 2u);
}

TEST_F(SimulatedCameraTest, FaultsFireOncePerOpen) {
  ASSERT_TRUE(camera_.InjectFault({CameraFault::Kind::kDrop, 1, 1}).ok());
  for (int session = 0; session < 2; ++session) {
    OpenAndStart();
    EXPECT_EQ(NextSequence(), 0u);
    EXPECT_EQ(NextSequence(), 2u);
    EXPECT_EQ(NextSequence(), 3u);
    camera_.Close();
  }
  EXPECT_EQ(camera_.counters().dropped, 2u);
}

TEST_F(SimulatedCameraTest, FaultPathsDoNotAllocate) {
  ASSERT_TRUE(AllocationCounterActive());
  ASSERT_TRUE(camera_.InjectFault({CameraFault::Kind::kDrop, 1, 2}).ok());
  ASSERT_TRUE(camera_.InjectFault({CameraFault::Kind::kStall, 4, 2}).ok());
  ASSERT_TRUE(camera_.InjectFault({CameraFault::Kind::kDisconnect, 5, 2}).ok());
  ASSERT_TRUE(camera_.InjectFault({CameraFault::Kind::kCorruptSize, 6, 1}).ok());
  OpenAndStart();
  AllocationScope scope;
  int ok = 0, failed = 0;
  for (int i = 0; i < 12; ++i) {
    Result<Frame> f = camera_.Capture(milliseconds(10));
    (f.ok() ? ok : failed) += 1;
  }
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(failed, 5);  // 2 stalls, 2 unplugged calls, 1 corrupt frame
  EXPECT_EQ(ok, 7);
}

TEST_F(SimulatedCameraTest, FiniteSourceEndsWithOutOfRange) {
  SimulatedCameraConfig c = Config();
  c.frame_count = 2;
  SimulatedCamera finite(c, &source_, &clock_);
  ASSERT_TRUE(finite.Open().ok());
  ASSERT_TRUE(finite.Start().ok());
  EXPECT_TRUE(finite.Capture(milliseconds(1)).ok());
  EXPECT_TRUE(finite.Capture(milliseconds(1)).ok());
  EXPECT_EQ(finite.Capture(milliseconds(1)).status().code(), StatusCode::kOutOfRange);
}

TEST_F(SimulatedCameraTest, FaultScheduleIsBoundedAndValidated) {
  EXPECT_EQ(camera_.InjectFault({CameraFault::Kind::kStall, 0, 0}).code(),
            StatusCode::kInvalidArgument);
  for (std::size_t i = 0; i < SimulatedCamera::kMaxFaults; ++i)
    ASSERT_TRUE(camera_.InjectFault({CameraFault::Kind::kDrop, 100 + i, 1}).ok());
  EXPECT_EQ(camera_.InjectFault({CameraFault::Kind::kDrop, 1, 1}).code(),
            StatusCode::kResourceExhausted);
}

TEST_F(SimulatedCameraTest, RejectsAnOddYuyvWidth) {
  SimulatedCameraConfig c = Config();
  c.format = dsp::PixelFormat::kYuyv;
  c.width = 41;
  SimulatedCamera odd(c, &source_, &clock_);
  EXPECT_EQ(odd.Open().code(), StatusCode::kInvalidArgument);
}

TEST(SyntheticSkySource, RendersEveryFormatWithTheSameLuminance) {
  SyntheticSkySource source;
  constexpr int kW = 16, kH = 12;
  std::uint8_t yuyv[kW * 2 * kH];
  std::uint8_t rgb[kW * 3 * kH];
  ASSERT_TRUE(source.Render(7, {yuyv, kW, kH, kW * 2, dsp::PixelFormat::kYuyv}, nullptr).ok());
  ASSERT_TRUE(source.Render(7, {rgb, kW, kH, kW * 3, dsp::PixelFormat::kRgb24}, nullptr).ok());
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const std::uint8_t g = source.GreyAt(7, x, y, kW, kH);
      EXPECT_EQ(yuyv[y * kW * 2 + 2 * x], g);
      EXPECT_EQ(yuyv[y * kW * 2 + 2 * x + 1], 128);
      EXPECT_EQ(rgb[y * kW * 3 + 3 * x + 1], g);
    }
  }
}

TEST(SyntheticSkySource, LooksLikeAnUpwardFisheye) {
  // Independent expectations: the zenith (image centre) is sky, the corners are outside
  // the lens circle (black), and the horizon ring has both sky and obstacles.
  SyntheticSkySource source;
  EXPECT_EQ(source.GreyAt(0, 50, 50, 100, 100), 220);
  EXPECT_EQ(source.GreyAt(0, 0, 0, 100, 100), 0);
  int sky = 0, obstacle = 0;
  for (int a = 0; a < 360; ++a) {
    const double rad = a * 3.14159265358979 / 180.0;
    const int x = 50 + static_cast<int>(45.0 * std::cos(rad));
    const int y = 50 + static_cast<int>(45.0 * std::sin(rad));
    const std::uint8_t v = source.GreyAt(0, x, y, 100, 100);
    sky += v == 220;
    obstacle += v == 40;
  }
  EXPECT_GT(sky, 10);
  EXPECT_GT(obstacle, 10);
}

// A live simulated run (`paced`): frames are due one interval apart from Start(), on the
// real clock, as a camera delivers them.
TEST(SimulatedCameraPacing, APacedCameraDeliversFramesAtItsRate) {
  SimulatedCameraConfig c;
  c.width = 16;
  c.height = 16;
  c.frame_interval = milliseconds(20);
  c.paced = true;
  SyntheticSkySource sky;
  MonotonicClock clock;
  SimulatedCamera camera(c, &sky, &clock);
  ASSERT_TRUE(camera.Open().ok());
  // Read before Start(): frame 0 is due at the time Start() reads, frame 3 three intervals
  // later. Read after it, the test's zero was late by Start()'s own time and the span came
  // out short under emulation (59.98 ms in one aarch64 qemu run).
  const Nanoseconds start = clock.Now();
  ASSERT_TRUE(camera.Start().ok());
  for (int i = 0; i < 4; ++i)
    ASSERT_TRUE(camera.Capture(milliseconds(100)).ok());
  EXPECT_GE(clock.Now() - start, milliseconds(60));
}

// A source that knows its frames' times and length (a trajectory) stamps and ends the run;
// a frame it cannot render is the camera's error, naming the camera and the frame.
TEST(SimulatedCameraSource, TheSourcesTimesLengthAndErrorsAreTheCameras) {
  class Source final : public FrameSource {
   public:
    std::uint64_t frame_count() const override { return 3; }
    std::optional<Nanoseconds> TimeOf(std::uint64_t index) const override {
      return milliseconds(250) * static_cast<std::int64_t>(index + 1);
    }
    Status Render(std::uint64_t index, dsp::MutableImageView out, std::optional<Pose>*) override {
      if (index == 1)
        return Status::Error(StatusCode::kDataLoss, "no frame 1 here");
      out.Row(0)[0] = 1;
      return Status::Ok();
    }
  };
  SimulatedCameraConfig c;
  c.name = "sim:test";
  c.width = 8;
  c.height = 8;
  Source source;
  ManualClock clock{milliseconds(5000)};
  SimulatedCamera camera(c, &source, &clock);
  ASSERT_TRUE(camera.Open().ok());
  ASSERT_TRUE(camera.Start().ok());
  Result<Frame> first = camera.Capture(milliseconds(1));
  ASSERT_TRUE(first.ok()) << first.status().message();
  EXPECT_EQ(first->timestamp, milliseconds(250));
  Result<Frame> broken = camera.Capture(milliseconds(1));
  ASSERT_FALSE(broken.ok());
  EXPECT_EQ(broken.status().code(), StatusCode::kDataLoss);
  EXPECT_NE(std::string(broken.status().message()).find("sim:test: frame 1"), std::string::npos)
      << broken.status().message();
  Result<Frame> third = camera.Capture(milliseconds(1));
  ASSERT_TRUE(third.ok()) << third.status().message();
  EXPECT_EQ(third->sequence, 2u);
  EXPECT_EQ(third->timestamp, milliseconds(750));
  EXPECT_EQ(camera.Capture(milliseconds(1)).status().code(), StatusCode::kOutOfRange);
}

}  // namespace
}  // namespace skyloc::drivers
