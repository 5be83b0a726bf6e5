// [camera] fps reaches a libcamera camera (HIL VM only, with SKYLOC_TEST_LIBCAMERA_CAMERA,
// as the compliance suite's libcamera instance): the driver sets FrameDurationLimits when
// the camera lists that control, and otherwise says once, on stderr, that it cannot, and
// streams at the camera's own rate. No frame timing is asserted: what is checked is the
// driver's decision and what it says.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "support/status_assertions.h"
#include "test_env.h"

#if SKYLOC_WITH_LIBCAMERA
#include "skyloc/drivers/libcamera_camera.h"
#endif

namespace skyloc::drivers {
namespace {

#if SKYLOC_WITH_LIBCAMERA
// What a camera asked for `fps` did over `starts` Start()/Stop() cycles.
struct Started {
  Status status;     // the first failure of Open() or Start(), if any
  double fps = -1;   // the driver's fps() after them
  std::string said;  // its stderr meanwhile (libcamera's own log lines too)
};

Started StartAndStop(const char* id, double fps, int starts) {
  LibcameraCameraConfig config;
  std::snprintf(config.camera_id, sizeof(config.camera_id), "%s", id);
  config.capture.fps = fps;
  LibcameraCamera camera(config);
  Started out;
  out.status = camera.Open();
  ::testing::internal::CaptureStderr();
  for (int i = 0; i < starts && out.status.ok(); ++i) {
    out.status = camera.Start();
    camera.Stop();
  }
  out.said = ::testing::internal::GetCapturedStderr();
  out.fps = camera.fps();
  camera.Close();
  return out;
}

// The camera the VM names, or nullptr off the VM.
const char* TestCameraId() {
  return testing::Env("SKYLOC_TEST_LIBCAMERA_CAMERA");
}

TEST(LibcameraFrameRate, AskedRateIsSetOrSaidOnce) {
  if (TestCameraId() == nullptr)
    GTEST_SKIP() << "no libcamera camera: set SKYLOC_TEST_LIBCAMERA_CAMERA=<id> or first (the "
                    "HIL VM does, with vimc)";
  const Started s = StartAndStop(TestCameraId(), 5, 2);  // a restart must not say it again
  ASSERT_OK(s.status);
  const std::string cannot = "fps 5 not set: the camera has no FrameDurationLimits control";
  if (s.fps == 5.0) {
    EXPECT_EQ(s.said.find(cannot), std::string::npos) << s.said;
  } else {
    EXPECT_EQ(s.fps, 0.0);
    const std::size_t first = s.said.find(cannot);
    ASSERT_NE(first, std::string::npos) << "the rate was dropped silently; stderr: " << s.said;
    EXPECT_EQ(s.said.find(cannot, first + 1), std::string::npos) << "said twice: " << s.said;
  }
}

TEST(LibcameraFrameRate, RateZeroLeavesTheCameraAloneSilently) {
  if (TestCameraId() == nullptr)
    GTEST_SKIP() << "no libcamera camera: set SKYLOC_TEST_LIBCAMERA_CAMERA";
  const Started s = StartAndStop(TestCameraId(), 0, 1);
  ASSERT_OK(s.status);
  EXPECT_EQ(s.fps, 0.0);
  EXPECT_EQ(s.said.find("FrameDurationLimits"), std::string::npos) << s.said;
}
#endif  // SKYLOC_WITH_LIBCAMERA

}  // namespace
}  // namespace skyloc::drivers
