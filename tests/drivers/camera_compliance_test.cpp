// One compliance suite for every Camera implementation, in the spirit of libcamera's
// lc-compliance: the same cases run against the simulated camera over each of its frame
// sources (the synthetic sky, the street the firmware's tests drive, a rendered world of
// the simulator), the dataset camera (replay, eval) over a small dataset written here, and
// the V4L2 driver over a scripted device (always), a V4L2 device
// (SKYLOC_TEST_V4L2_DEVICE) and a libcamera camera (SKYLOC_TEST_LIBCAMERA_CAMERA). Real instances
// are SKIPPED with the reason when no device is named or present; the HIL harness runs them inside
// a VM against vivid and vimc.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "skyloc/drivers/camera.h"
#include "skyloc/drivers/dataset.h"
#include "skyloc/drivers/frame_source.h"
#include "skyloc/drivers/simulated_camera.h"
#include "skyloc/platform/alloc_counter.h"
#include "skyloc/platform/clock.h"
#include "skyloc/sim/motion.h"
#include "skyloc/sim/rendered_source.h"
#include "skyloc/sim/street_source.h"
#include "skyloc/sim/world.h"
#include "support/scratch_dir.h"
#include "support/status_assertions.h"
#include "test_env.h"
#if SKYLOC_WITH_V4L2
#include "fake_v4l2_device.h"
#include "skyloc/drivers/v4l2_camera.h"
#endif
#if SKYLOC_WITH_LIBCAMERA
#include "skyloc/drivers/libcamera_camera.h"
#endif

namespace skyloc::drivers {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;

// Owns a camera and whatever it needs (a frame source, a clock).
class CameraUnderTest {
 public:
  virtual ~CameraUnderTest() = default;
  virtual Camera& camera() = 0;
};

struct CameraCase {
  const char* name;
  // The camera to test, or nullptr with *skip saying why it cannot be tested here.
  std::unique_ptr<CameraUnderTest> (*make)(std::string* skip);
  // Frame timestamps are CLOCK_MONOTONIC times (real devices), so they must lie near now.
  bool monotonic_clock_timestamps;
};

// --- the simulated camera ---
class SimUnderTest final : public CameraUnderTest {
 public:
  SimUnderTest() : camera_(Config(), &source_, &clock_) {}
  Camera& camera() override { return camera_; }

 private:
  static SimulatedCameraConfig Config() {
    SimulatedCameraConfig c;
    c.name = "sim:compliance";
    c.width = 96;
    c.height = 64;
    return c;
  }
  SyntheticSkySource source_;
  ManualClock clock_{seconds(100)};
  SimulatedCamera camera_;
};

std::unique_ptr<CameraUnderTest> MakeSim(std::string*) {
  return std::make_unique<SimUnderTest>();
}

// --- the simulated camera on the street (`camera.kind = "sim"`, sim_world = "street") ---
std::unique_ptr<CameraUnderTest> MakeStreet(std::string*) {
  class Under final : public CameraUnderTest {
   public:
    Under() : street_(Options()) {}
    Camera& camera() override { return street_.camera; }

   private:
    static sim::StreetOptions Options() {
      sim::StreetOptions o;
      o.width = 64;
      o.height = 48;
      o.seed = 7;
      o.speed_jitter = 0.2;
      return o;
    }
    sim::FilmedStreet street_;
  };
  return std::make_unique<Under>();
}

// --- the simulated camera in a world of the simulator (simulate, the demo) ---
std::unique_ptr<CameraUnderTest> MakeRendered(std::string* skip) {
  class Under final : public CameraUnderTest {
   public:
    Under(std::unique_ptr<sim::World> world, std::vector<sim::TrajectoryPoint> trajectory)
        : world_(std::move(world)),
          trajectory_(std::move(trajectory)),
          source_(world_.get(), trajectory_, Config()),
          camera_(source_.camera_config(), &source_, &clock_) {}
    Camera& camera() override { return camera_; }

   private:
    static sim::RenderedSourceConfig Config() {
      sim::RenderedSourceConfig c;
      c.lens = sim::DefaultSimLens(64, 48);
      return c;
    }
    std::unique_ptr<sim::World> world_;
    std::vector<sim::TrajectoryPoint> trajectory_;
    sim::RenderedSource source_;
    ManualClock clock_;
    SimulatedCamera camera_;
  };
  auto world = std::make_unique<sim::World>();
  std::vector<sim::TrajectoryPoint> trajectory;
  sim::MotionConfig motion;
  motion.max_frames = 40;
  if (Status s = sim::MakeProceduralWorld(sim::WorldKind::kRepetitive, 1, world.get()); !s.ok()) {
    ADD_FAILURE() << "cannot make the world: " << s.message();
    *skip = "setup failed";
    return nullptr;
  }
  if (Status s = sim::BuildTrajectory(world->route, world->route_closed, motion, &trajectory);
      !s.ok()) {
    ADD_FAILURE() << "cannot make the trajectory: " << s.message();
    *skip = "setup failed";
    return nullptr;
  }
  return std::make_unique<Under>(std::move(world), std::move(trajectory));
}

// --- the dataset camera (replay, eval) over a dataset written to its own scratch folder ---
std::unique_ptr<CameraUnderTest> MakeDataset(std::string* skip) {
  class Under final : public CameraUnderTest {
   public:
    explicit Under(std::unique_ptr<skyloc::testing::ScratchDir> scratch)
        : scratch_(std::move(scratch)), camera_(scratch_->path() + "/run") {}
    Camera& camera() override { return camera_; }

   private:
    std::unique_ptr<skyloc::testing::ScratchDir> scratch_;  // removed with the camera
    DatasetCamera camera_;
  };
  auto scratch = std::make_unique<skyloc::testing::ScratchDir>("skyloc_compliance_");
  // Frames of the synthetic sky, enough for the longest case (10 frames in one session).
  SimulatedCameraConfig config;
  config.width = 48;
  config.height = 32;
  SyntheticSkySource sky;
  ManualClock clock;
  SimulatedCamera source(config, &sky, &clock);
  DatasetWriter writer;
  Status s = writer.Open(scratch->path() + "/run", /*with_poses=*/true);
  if (s.ok())
    s = source.Open();
  if (s.ok())
    s = source.Start();
  for (int i = 0; s.ok() && i < 16; ++i) {
    Result<Frame> frame = source.Capture(Nanoseconds(0));
    s = frame.ok() ? writer.Append(frame->image, 0.1 * i, frame->pose) : frame.status();
  }
  if (s.ok())
    s = writer.Close();
  if (!s.ok()) {
    ADD_FAILURE() << "cannot write the dataset: " << s.message();
    *skip = "setup failed";
    return nullptr;
  }
  return std::make_unique<Under>(std::move(scratch));
}

// --- V4L2 ---
std::unique_ptr<CameraUnderTest> MakeV4l2(std::string* skip) {
#if SKYLOC_WITH_V4L2
  const char* device = testing::Env("SKYLOC_TEST_V4L2_DEVICE");
  if (device == nullptr) {
    *skip =
        "no V4L2 device: set SKYLOC_TEST_V4L2_DEVICE=/dev/videoN or driver:card (the HIL "
        "VM does, with vivid)";
    return nullptr;
  }
  class Under final : public CameraUnderTest {
   public:
    explicit Under(const V4l2CameraConfig& c) : camera_(c) {}
    Camera& camera() override { return camera_; }

   private:
    V4l2Camera camera_;
  };
  V4l2CameraConfig config;
  std::snprintf(config.device, sizeof(config.device), "%s", device);
  testing::EnvSize("SKYLOC_TEST_V4L2_SIZE", &config.capture.width, &config.capture.height);
  return std::make_unique<Under>(config);
#else
  *skip = "this build has no V4L2 driver (linux/videodev2.h missing)";
  return nullptr;
#endif
}

// --- the V4L2 driver over a scripted device: its code paths on every build machine ---
std::unique_ptr<CameraUnderTest> MakeV4l2Fake(std::string* skip) {
#if SKYLOC_WITH_V4L2
  (void)skip;
  class Under final : public CameraUnderTest {
   public:
    Under() : camera_(V4l2CameraConfig{}, &device_) {}
    Camera& camera() override { return camera_; }

   private:
    testing::FakeV4l2Device device_;
    V4l2Camera camera_;
  };
  return std::make_unique<Under>();
#else
  *skip = "this build has no V4L2 driver (linux/videodev2.h missing)";
  return nullptr;
#endif
}

// --- libcamera ---
std::unique_ptr<CameraUnderTest> MakeLibcamera(std::string* skip) {
#if SKYLOC_WITH_LIBCAMERA
  const char* id = testing::Env("SKYLOC_TEST_LIBCAMERA_CAMERA");
  if (id == nullptr) {
    *skip =
        "no libcamera camera: set SKYLOC_TEST_LIBCAMERA_CAMERA=<id> or first (the HIL VM "
        "does, with vimc)";
    return nullptr;
  }
  class Under final : public CameraUnderTest {
   public:
    explicit Under(const LibcameraCameraConfig& c) : camera_(c) {}
    Camera& camera() override { return camera_; }

   private:
    LibcameraCamera camera_;
  };
  LibcameraCameraConfig config;
  std::snprintf(config.camera_id, sizeof(config.camera_id), "%s", id);
  return std::make_unique<Under>(config);
#else
  *skip = "this build has no libcamera driver (libcamera-dev not installed for the target)";
  return nullptr;
#endif
}

const CameraCase kCameraCases[] = {
    {"Simulated", MakeSim, false},
    {"SimulatedStreet", MakeStreet, false},
    {"SimulatedRendered", MakeRendered, false},
    {"Dataset", MakeDataset, false},
    {"V4l2FakeDevice", MakeV4l2Fake, false},
    {"V4l2", MakeV4l2, true},
    {"Libcamera", MakeLibcamera, true},
};

// The cameras whose Capture() can be proven allocation-free with the process-wide
// allocation counter. Not libcamera: its own threads allocate for every request
// (queued method calls, Signal::emit), which the counter cannot tell apart from ours;
// LibcameraCamera's part (SPSC hand-over, eventfd, request reuse) allocates nothing by
// construction. Not the dataset camera: replay decodes a file in each Capture(), the one
// exception camera.h makes on purpose (docs/DRIVERS.md, "The camera contract").
const CameraCase kAllocationFreeCases[] = {kCameraCases[0], kCameraCases[1], kCameraCases[2],
                                           kCameraCases[4], kCameraCases[5]};

constexpr Nanoseconds kFrameTimeout = seconds(5);  // vimc under QEMU TCG: ~6 fps
constexpr int kFrames = 8;

class CameraCompliance : public ::testing::TestWithParam<CameraCase> {
 protected:
  void SetUp() override {
    std::string skip;
    under_ = GetParam().make(&skip);
    if (!under_)
      GTEST_SKIP() << skip;
  }
  Camera& camera() { return under_->camera(); }

  // Captures `n` frames and checks each against what the camera reports.
  void CaptureFrames(int n) {
    const CameraInfo& info = camera().info();
    for (int i = 0; i < n; ++i) {
      Result<Frame> frame = camera().Capture(kFrameTimeout);
      ASSERT_TRUE(frame.ok()) << "frame " << i << ": " << frame.status().message();
      const dsp::ImageView& image = frame->image;
      ASSERT_NE(image.data, nullptr);
      EXPECT_EQ(image.width, info.width);
      EXPECT_EQ(image.height, info.height);
      EXPECT_EQ(image.format, info.format);
      EXPECT_GE(image.stride, image.RowBytes());
      if (have_last_) {
        EXPECT_GT(frame->sequence, last_sequence_) << "frame " << i;
        EXPECT_GT(frame->timestamp, last_timestamp_) << "frame " << i;
      }
      if (GetParam().monotonic_clock_timestamps) {
        // Frames are stamped on CLOCK_MONOTONIC (not CLOCK_REALTIME, which would be decades
        // off): near now. Not strictly before now: vivid stamps a frame with its nominal
        // frame time, which can lie a frame period (~35 ms seen) after the dequeue.
        const Nanoseconds now = MonotonicClock().Now();
        EXPECT_LT(frame->timestamp, now + seconds(1));
        EXPECT_GT(frame->timestamp, now - seconds(10));
      }
      have_last_ = true;
      last_sequence_ = frame->sequence;
      last_timestamp_ = frame->timestamp;
      // The camera films something: the buffer is not one flat value.
      const auto [lo, hi] = std::minmax_element(image.Row(image.height / 2),
                                                image.Row(image.height / 2) + image.RowBytes());
      EXPECT_LT(*lo, *hi) << "frame " << i << " middle row is flat";
    }
  }

  std::unique_ptr<CameraUnderTest> under_;
  bool have_last_ = false;
  std::uint64_t last_sequence_ = 0;
  Nanoseconds last_timestamp_{0};
};

TEST_P(CameraCompliance, OpenStartCaptureStopClose) {
  ASSERT_OK(camera().Open());
  EXPECT_EQ(camera().state(), Camera::State::kOpen);
  EXPECT_GT(camera().info().width, 0);
  EXPECT_GT(camera().info().height, 0);
  ASSERT_OK(camera().Start());
  EXPECT_EQ(camera().state(), Camera::State::kStreaming);
  CaptureFrames(kFrames);
  EXPECT_EQ(camera().counters().frames, static_cast<std::uint64_t>(kFrames));
  EXPECT_EQ(camera().counters().errors, 0u);
  camera().Stop();
  EXPECT_EQ(camera().state(), Camera::State::kOpen);
  camera().Close();
  EXPECT_EQ(camera().state(), Camera::State::kClosed);
}

TEST_P(CameraCompliance, RestartsStreamAndReopens) {
  for (int session = 0; session < 2; ++session) {
    ASSERT_OK(camera().Open()) << "session " << session;
    for (int run = 0; run < 2; ++run) {
      ASSERT_OK(camera().Start()) << "session " << session << " run " << run;
      // Sequence numbers and timestamps keep increasing across Stop/Start.
      CaptureFrames(3);
      camera().Stop();
    }
    camera().Close();
    have_last_ = false;  // a new session may number frames afresh
  }
  EXPECT_EQ(camera().counters().frames, 12u);
}

TEST_P(CameraCompliance, RejectsCallsInTheWrongState) {
  // Closed.
  Result<Frame> early = camera().Capture(milliseconds(1));
  EXPECT_EQ(early.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(camera().Start().code(), StatusCode::kFailedPrecondition);
  camera().Stop();   // harmless
  camera().Close();  // harmless
  EXPECT_EQ(camera().state(), Camera::State::kClosed);
  // Open.
  ASSERT_OK(camera().Open());
  const Status twice = camera().Open();
  EXPECT_EQ(twice.code(), StatusCode::kFailedPrecondition);
  // The error names the camera, so a log line says which device was misused.
  EXPECT_NE(std::string(twice.message()).find(camera().info().name), std::string::npos)
      << twice.message();
  EXPECT_EQ(camera().Capture(milliseconds(1)).status().code(), StatusCode::kFailedPrecondition);
  // Streaming.
  ASSERT_OK(camera().Start());
  EXPECT_EQ(camera().Start().code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(camera().Open().code(), StatusCode::kFailedPrecondition);
  camera().Stop();
  EXPECT_EQ(camera().Capture(milliseconds(1)).status().code(), StatusCode::kFailedPrecondition);
  camera().Close();
  EXPECT_EQ(camera().counters().errors, 3u);
}

TEST_P(CameraCompliance, CloseWhileStreamingStopsFirst) {
  ASSERT_OK(camera().Open());
  ASSERT_OK(camera().Start());
  CaptureFrames(1);
  camera().Close();
  EXPECT_EQ(camera().state(), Camera::State::kClosed);
  ASSERT_OK(camera().Open());
  ASSERT_OK(camera().Start());
  have_last_ = false;
  CaptureFrames(1);
}

TEST_P(CameraCompliance, ZeroTimeoutReturnsAFrameOrDeadlineExceeded) {
  ASSERT_OK(camera().Open());
  ASSERT_OK(camera().Start());
  for (int i = 0; i < 3; ++i) {
    Result<Frame> frame = camera().Capture(Nanoseconds(0));
    if (!frame.ok()) {
      EXPECT_EQ(frame.status().code(), StatusCode::kDeadlineExceeded) << frame.status().message();
      // The frame loop passes a capture error on as it is: it must say which camera failed.
      EXPECT_NE(std::string(frame.status().message()).find(camera().info().name), std::string::npos)
          << frame.status().message();
    }
  }
  // The stream is still healthy afterwards.
  CaptureFrames(2);
}

class CameraCaptureAllocation : public CameraCompliance {};

TEST_P(CameraCaptureAllocation, CaptureDoesNotAllocate) {
  ASSERT_TRUE(AllocationCounterActive());
  ASSERT_OK(camera().Open());
  ASSERT_OK(camera().Start());
  CaptureFrames(2);  // warm-up: the first frames may page in buffers
  std::uint64_t failures = 0;
  AllocationScope scope;
  for (int i = 0; i < kFrames; ++i) {
    Result<Frame> frame = camera().Capture(kFrameTimeout);
    failures += frame.ok() ? 0u : 1u;
  }
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(failures, 0u);
}

// Shown by --gtest_list_tests (and so in CTest's test names) instead of raw bytes.
void PrintTo(const CameraCase& c, std::ostream* os) {
  *os << c.name;
}

std::string CaseName(const ::testing::TestParamInfo<CameraCase>& info) {
  return info.param.name;
}

INSTANTIATE_TEST_SUITE_P(AllCameras, CameraCompliance, ::testing::ValuesIn(kCameraCases), CaseName);
INSTANTIATE_TEST_SUITE_P(AllocationFreeCameras, CameraCaptureAllocation,
                         ::testing::ValuesIn(kAllocationFreeCases), CaseName);

}  // namespace
}  // namespace skyloc::drivers
