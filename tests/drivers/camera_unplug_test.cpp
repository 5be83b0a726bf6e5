// A real camera disappearing mid-stream and coming back (HIL VM only; contract in
// docs/HIL.md and docs/DRIVERS.md), through each driver that reconnects by itself: V4L2
// on vivid and libcamera on vimc. The test pulls the camera itself by unbinding its
// platform device from the driver, so nothing depends on timing between processes:
//
//   SKYLOC_TEST_V4L2_DEVICE           the V4L2 camera, preferably by driver:card (a
//                                     rebound device may get another /dev/video number)
//   SKYLOC_TEST_V4L2_UNBIND / _BIND   the driver's sysfs unbind / bind files
//   SKYLOC_TEST_V4L2_PLATFORM_DEVICE  what to write to them (vivid.0)
//   SKYLOC_TEST_LIBCAMERA_CAMERA      the libcamera camera (id, or first), with
//   SKYLOC_TEST_LIBCAMERA_UNBIND / _BIND / _PLATFORM_DEVICE  (vimc's, vimc.0)
//   SKYLOC_TEST_GPIOCHIP, SKYLOC_TEST_GPIO_LINES, SKYLOC_TEST_GPIO_SIM_DIR
//                                     status lines, read back through gpio-sim's sysfs
//
// While frames flow the status output shows LOCALISED; when Capture() reports the camera
// gone the test drives the status lines to the safe state, as the pipeline does, and
// checks on the simulated pins that they really are off. Expected: one kUnavailable error
// naming the camera, frames again after the bind, a restart counted, sequence numbers
// still increasing.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <memory>
#include <string>

#include "skyloc/drivers/simulated_status_output.h"
#include "skyloc/drivers/status_output.h"
#include "skyloc/platform/clock.h"
#include "test_env.h"
#if SKYLOC_WITH_V4L2
#include "skyloc/drivers/v4l2_camera.h"
#endif
#if SKYLOC_WITH_LIBCAMERA
#include "skyloc/drivers/libcamera_camera.h"
#endif
#if SKYLOC_WITH_GPIOD
#include "gpio_sim.h"
#include "skyloc/drivers/gpio_status_output.h"
#endif

namespace skyloc::drivers {
namespace {

#if SKYLOC_WITH_V4L2 || SKYLOC_WITH_LIBCAMERA

using std::chrono::seconds;

bool WriteSysfs(const char* path, const char* value) {
  std::FILE* f = std::fopen(path, "w");
  if (f == nullptr)
    return false;
  const bool ok = std::fputs(value, f) >= 0;
  return std::fclose(f) == 0 && ok;
}

// The status lines: on gpio-sim when the harness names a chip, else the simulated twin.
class StatusLinesUnderTest {
 public:
  Status Open() {
#if SKYLOC_WITH_GPIOD
    if (const char* chip = testing::Env("SKYLOC_TEST_GPIOCHIP")) {
      GpioStatusOutputConfig c;
      std::snprintf(c.chip, sizeof(c.chip), "%s", chip);
      if (const char* lines = testing::Env("SKYLOC_TEST_GPIO_LINES"))
        std::sscanf(lines, "%u,%u,%u", &c.lines[0], &c.lines[1], &c.lines[2]);
      offsets_ = c.lines;
      auto gpio = std::make_unique<GpioStatusOutput>(c);
      SKYLOC_TRY(gpio->Open());
      Result<testing::GpioSimPins> pins = testing::GpioSimPins::Find(gpio->chip_name());
      if (!pins.ok())
        return pins.status();
      pins_ = std::make_unique<testing::GpioSimPins>(std::move(pins).value());
      output_ = std::move(gpio);
      return Status::Ok();
    }
#endif
    auto sim = std::make_unique<SimulatedStatusOutput>(SimulatedStatusOutputConfig{}, &clock_);
    SKYLOC_TRY(sim->Open());
    sim_ = sim.get();
    output_ = std::move(sim);
    return Status::Ok();
  }
  StatusOutput& output() {
    return *output_;
  }
  const char* kind() const {
    return sim_ != nullptr ? "simulated" : "gpio-sim";
  }

  // "LOST SEARCHING LOCALISED" levels as read back, e.g. "001".
  std::string Levels() {
    std::string s;
    for (std::size_t i = 0; i < 3; ++i) {
      if (sim_ != nullptr) {
        s += sim_->Level(i) ? '1' : '0';
        continue;
      }
#if SKYLOC_WITH_GPIOD
      Result<bool> level = pins_->Level(offsets_[i]);
      if (!level.ok())
        return level.status().message();
      s += *level ? '1' : '0';
#endif
    }
    return s;
  }

 private:
  MonotonicClock clock_;
  std::unique_ptr<StatusOutput> output_;
  SimulatedStatusOutput* sim_ = nullptr;
#if SKYLOC_WITH_GPIOD
  std::unique_ptr<testing::GpioSimPins> pins_;
  std::array<unsigned, 3> offsets_{};
#endif
};

// Streams, pulls the camera (unbind), checks it is reported gone (error `gone`, naming the
// camera) with the status lines safe, and plugs it back (bind). A driver that reopens by
// itself (V4L2) must then resume the stream with its numbering going on; one that cannot
// (libcamera: its header says why) must close without crashing and refuse to open again
// in this process with an error, not an abort.
void PullAndPlugBack(Camera& camera, const char* unbind, const char* bind,
                     const char* platform_device, StatusCode gone, bool reopens_itself) {
  StatusLinesUnderTest status;
  const Status status_open = status.Open();
  ASSERT_TRUE(status_open.ok()) << status_open.message();
  const Status open = camera.Open();
  ASSERT_TRUE(open.ok()) << open.message();
  ASSERT_TRUE(camera.Start().ok());
  std::printf("camera %s, status lines: %s\n", camera.info().name, status.kind());

  std::uint64_t last = 0;
  for (int i = 0; i < 3; ++i) {
    Result<Frame> f = camera.Capture(seconds(5));
    ASSERT_TRUE(f.ok()) << f.status().message();
    last = f->sequence;
    ASSERT_TRUE(status.output().Show(LocalisationState::kLocalised, 1.0f, f->timestamp).ok());
  }
  EXPECT_EQ(status.Levels(), "001");

  // Pull the camera.
  ASSERT_TRUE(WriteSysfs(unbind, platform_device))
      << "cannot write " << platform_device << " to " << unbind;
  int unavailable = 0;
  for (int i = 0; i < 10 && unavailable < 3; ++i) {
    Result<Frame> f = camera.Capture(seconds(1));
    if (f.ok()) {  // a frame already in flight
      last = f->sequence;
      continue;
    }
    ASSERT_TRUE(f.status().code() == gone || f.status().code() == StatusCode::kDeadlineExceeded)
        << StatusCodeName(f.status().code()) << ": " << f.status().message();
    if (f.status().code() != gone)
      continue;
    if (unavailable++ == 0) {
      std::printf("camera gone: %s\n", f.status().message());
      EXPECT_NE(std::string(f.status().message()).find(camera.info().name), std::string::npos)
          << "the error should name the camera: " << f.status().message();
    }
    ASSERT_TRUE(status.output().SafeState().ok());
    EXPECT_EQ(status.Levels(), "000") << "status lines not safe while the camera is gone";
  }
  ASSERT_GE(unavailable, 3) << "the driver never reported the camera gone (" << StatusCodeName(gone)
                            << ")";
  EXPECT_EQ(camera.counters().restarts, 0u);

  if (!reopens_itself) {
    camera.Stop();
    camera.Close();  // must not abort inside libcamera
    ASSERT_TRUE(WriteSysfs(bind, platform_device))
        << "cannot write " << platform_device << " to " << bind;
    const Status again = camera.Open();
    EXPECT_FALSE(again.ok()) << "reopened in the same process";
    std::printf("open again in this process: %s\n", again.message());
    EXPECT_NE(std::string(again.message()).find("restart"), std::string::npos) << again.message();
    status.output().Close();
    return;
  }

  // Plug it back.
  ASSERT_TRUE(WriteSysfs(bind, platform_device))
      << "cannot write " << platform_device << " to " << bind;
  bool resumed = false;
  for (int i = 0; i < 30 && !resumed; ++i) {
    Result<Frame> f = camera.Capture(seconds(1));
    if (!f.ok())
      continue;
    EXPECT_GT(f->sequence, last);
    ASSERT_TRUE(status.output().Show(LocalisationState::kLocalised, 1.0f, f->timestamp).ok());
    resumed = true;
  }
  ASSERT_TRUE(resumed) << "no frame within 30 s of binding the camera again";
  EXPECT_EQ(status.Levels(), "001");
  EXPECT_GE(camera.counters().restarts, 1u);
  std::printf("recovered: %llu frames, %llu restarts, %llu errors, %llu dropped (%s)\n",
              static_cast<unsigned long long>(camera.counters().frames),
              static_cast<unsigned long long>(camera.counters().restarts),
              static_cast<unsigned long long>(camera.counters().errors),
              static_cast<unsigned long long>(camera.counters().dropped), camera.info().name);
  camera.Close();
  status.output().Close();
}

#endif  // SKYLOC_WITH_V4L2 || SKYLOC_WITH_LIBCAMERA

#if SKYLOC_WITH_V4L2
TEST(V4l2Unplug, CameraPulledMidStreamIsReportedStatusGoesSafeAndStreamRecovers) {
  const char* device = testing::Env("SKYLOC_TEST_V4L2_DEVICE");
  const char* unbind = testing::Env("SKYLOC_TEST_V4L2_UNBIND");
  const char* bind = testing::Env("SKYLOC_TEST_V4L2_BIND");
  const char* platform_device = testing::Env("SKYLOC_TEST_V4L2_PLATFORM_DEVICE");
  if (device == nullptr || unbind == nullptr || bind == nullptr || platform_device == nullptr) {
    GTEST_SKIP() << "needs SKYLOC_TEST_V4L2_DEVICE, SKYLOC_TEST_V4L2_UNBIND, "
                    "SKYLOC_TEST_V4L2_BIND and SKYLOC_TEST_V4L2_PLATFORM_DEVICE (the HIL VM "
                    "sets them, with vivid)";
  }
  V4l2CameraConfig config;
  std::snprintf(config.device, sizeof(config.device), "%s", device);
  testing::EnvSize("SKYLOC_TEST_V4L2_SIZE", &config.capture.width, &config.capture.height);
  config.recovery.backoff_max = std::chrono::milliseconds(500);
  V4l2Camera camera(config);
  PullAndPlugBack(camera, unbind, bind, platform_device, StatusCode::kUnavailable,
                  /*reopens_itself=*/true);
}
#endif  // SKYLOC_WITH_V4L2

#if SKYLOC_WITH_LIBCAMERA
TEST(LibcameraUnplug, CameraPulledMidStreamIsReportedStatusGoesSafeAndClosesCleanly) {
  const char* id = testing::Env("SKYLOC_TEST_LIBCAMERA_CAMERA");
  const char* unbind = testing::Env("SKYLOC_TEST_LIBCAMERA_UNBIND");
  const char* bind = testing::Env("SKYLOC_TEST_LIBCAMERA_BIND");
  const char* platform_device = testing::Env("SKYLOC_TEST_LIBCAMERA_PLATFORM_DEVICE");
  if (id == nullptr || unbind == nullptr || bind == nullptr || platform_device == nullptr) {
    GTEST_SKIP() << "needs SKYLOC_TEST_LIBCAMERA_CAMERA, SKYLOC_TEST_LIBCAMERA_UNBIND, "
                    "SKYLOC_TEST_LIBCAMERA_BIND and SKYLOC_TEST_LIBCAMERA_PLATFORM_DEVICE (the "
                    "HIL VM sets them, with vimc)";
  }
  LibcameraCameraConfig config;
  std::snprintf(config.camera_id, sizeof(config.camera_id), "%s", id);
  LibcameraCamera camera(config);
  PullAndPlugBack(camera, unbind, bind, platform_device, StatusCode::kFailedPrecondition,
                  /*reopens_itself=*/false);
}
#endif  // SKYLOC_WITH_LIBCAMERA

}  // namespace
}  // namespace skyloc::drivers
