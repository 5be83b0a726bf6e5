// A real V4L2 device disappearing mid-stream and coming back (HIL VM only): the harness
// names the device (SKYLOC_TEST_V4L2_DEVICE) and how to unplug it
// (SKYLOC_TEST_V4L2_UNBIND=<sysfs driver dir>:<device>, e.g.
// /sys/bus/platform/drivers/vivid:vivid.0). The test unbinds the driver while streaming,
// expects Capture() to report kUnavailable (never a crash or a stale frame), binds it
// again and expects frames to resume with a restart counted and the sequence increasing.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <string>

#include "test_env.h"
#if SKYLOC_WITH_V4L2
#include "skyloc/drivers/v4l2_camera.h"
#endif

namespace skyloc::drivers {
namespace {

#if SKYLOC_WITH_V4L2

using std::chrono::seconds;

bool WriteSysfs(const std::string& path, const std::string& value) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr)
    return false;
  const bool ok = std::fputs(value.c_str(), f) >= 0;
  return std::fclose(f) == 0 && ok;
}

TEST(V4l2Hotplug, UnbindMidStreamIsReportedAndRecovered) {
  const char* device = testing::Env("SKYLOC_TEST_V4L2_DEVICE");
  const char* unbind = testing::Env("SKYLOC_TEST_V4L2_UNBIND");
  if (device == nullptr || unbind == nullptr) {
    GTEST_SKIP() << "needs SKYLOC_TEST_V4L2_DEVICE and SKYLOC_TEST_V4L2_UNBIND=<sysfs driver "
                    "dir>:<device> (the HIL VM sets them, with vivid)";
  }
  const std::string spec = unbind;
  const std::size_t colon = spec.rfind(':');
  ASSERT_NE(colon, std::string::npos)
      << "SKYLOC_TEST_V4L2_UNBIND='" << spec << "' is not <driver dir>:<device>";
  const std::string driver_dir = spec.substr(0, colon);
  const std::string name = spec.substr(colon + 1);

  V4l2CameraConfig config;
  std::snprintf(config.device, sizeof(config.device), "%s", device);
  testing::EnvSize("SKYLOC_TEST_V4L2_SIZE", &config.width, &config.height);
  config.recovery.backoff_max = std::chrono::milliseconds(500);
  V4l2Camera camera(config);
  const Status open = camera.Open();
  ASSERT_TRUE(open.ok()) << open.message();
  ASSERT_TRUE(camera.Start().ok());
  std::uint64_t last = 0;
  for (int i = 0; i < 3; ++i) {
    Result<Frame> f = camera.Capture(seconds(5));
    ASSERT_TRUE(f.ok()) << f.status().message();
    last = f->sequence;
  }

  ASSERT_TRUE(WriteSysfs(driver_dir + "/unbind", name)) << "cannot unbind " << spec;
  bool reported = false;
  for (int i = 0; i < 10 && !reported; ++i) {
    Result<Frame> f = camera.Capture(seconds(1));
    if (f.ok()) {
      last = f->sequence;  // a frame already in flight
      continue;
    }
    EXPECT_TRUE(f.status().code() == StatusCode::kUnavailable ||
                f.status().code() == StatusCode::kDeadlineExceeded)
        << f.status().message();
    reported = f.status().code() == StatusCode::kUnavailable;
  }
  EXPECT_TRUE(reported) << "the driver never reported the device gone";

  ASSERT_TRUE(WriteSysfs(driver_dir + "/bind", name)) << "cannot bind " << spec;
  bool resumed = false;
  for (int i = 0; i < 30 && !resumed; ++i) {
    Result<Frame> f = camera.Capture(seconds(1));
    if (f.ok()) {
      EXPECT_GT(f->sequence, last);
      resumed = true;
    }
  }
  EXPECT_TRUE(resumed) << "no frame within 30 s of rebinding";
  EXPECT_GE(camera.counters().restarts, 1u);
}

#endif  // SKYLOC_WITH_V4L2

}  // namespace
}  // namespace skyloc::drivers
