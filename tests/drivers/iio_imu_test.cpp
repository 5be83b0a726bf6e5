// The IIO IMU driver's parsing and error paths (over the fake tree of fake_iio_device.h),
// the mounting helpers, and the simulated IMU's faults and pacing. The behaviour every IMU
// shares is in imu_device_compliance_test.cpp.
#include "skyloc/drivers/iio_imu.h"

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "fake_iio_device.h"
#include "skyloc/drivers/imu_device.h"
#include "skyloc/drivers/simulated_imu.h"
#include "skyloc/platform/clock.h"
#include "support/scratch_dir.h"

namespace skyloc::drivers {
namespace {

using std::chrono::milliseconds;
using testing::FakeIioDevice;

bool Contains(const Status& s, const char* text) {
  return std::string(s.message()).find(text) != std::string::npos;
}

TEST(IioScanType, ParsesTheKernelFormats) {
  Result<IioScanType> t = ParseIioScanType("le:s16/16>>0");
  ASSERT_TRUE(t.ok()) << t.status().message();
  EXPECT_FALSE(t->big_endian);
  EXPECT_TRUE(t->is_signed);
  EXPECT_EQ(t->realbits, 16);
  EXPECT_EQ(t->storagebits, 16);
  EXPECT_EQ(t->shift, 0);
  EXPECT_EQ(t->bytes(), 2u);

  t = ParseIioScanType("be:u12/16>>4\n");
  ASSERT_TRUE(t.ok()) << t.status().message();
  EXPECT_TRUE(t->big_endian);
  EXPECT_FALSE(t->is_signed);
  EXPECT_EQ(t->realbits, 12);
  EXPECT_EQ(t->shift, 4);

  t = ParseIioScanType("le:s16/32X2>>0");
  ASSERT_TRUE(t.ok()) << t.status().message();
  EXPECT_EQ(t->repeat, 2);
  EXPECT_EQ(t->bytes(), 8u);

  t = ParseIioScanType("le:s64/64>>0");
  ASSERT_TRUE(t.ok());
  EXPECT_EQ(t->bytes(), 8u);

  for (const char* bad : {"", "le:s16", "xx:s16/16>>0", "le:q16/16>>0", "le:s17/16>>0",
                          "le:s16/12>>0", "le:s12/16>>8", "le:s16/16>>0junk", "le:s16/16X0>>0"}) {
    Result<IioScanType> r = ParseIioScanType(bad);
    EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument) << "'" << bad << "'";
  }
}

TEST(IioScanType, ExtractsShiftedMaskedSignExtendedValues) {
  const std::uint8_t le_minus_two[2] = {0xfe, 0xff};
  EXPECT_EQ(IioScanValue(*ParseIioScanType("le:s16/16>>0"), le_minus_two), -2);
  EXPECT_EQ(IioScanValue(*ParseIioScanType("le:u16/16>>0"), le_minus_two), 0xfffe);
  const std::uint8_t be_16399[2] = {0x40, 0x0f};
  EXPECT_EQ(IioScanValue(*ParseIioScanType("be:s16/16>>0"), be_16399), 16399);
  // 12 bits left-aligned in 16 with garbage in the low nibble: 0x800 is -2048.
  const std::uint8_t be_shifted[2] = {0x80, 0x0f};
  EXPECT_EQ(IioScanValue(*ParseIioScanType("be:s12/16>>4"), be_shifted), -2048);
  // 14 bits, shift 2, top two bits garbage (not sign).
  const std::uint8_t le_14[2] = {0x04, 0xc0};  // 0xc004 >> 2 = 0x3001 -> 14 bits 0x3001 < 0
  EXPECT_EQ(IioScanValue(*ParseIioScanType("le:s14/16>>2"), le_14), 0x3001 - 0x4000);
  const std::uint8_t ts[8] = {0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x00};
  EXPECT_EQ(IioScanValue(*ParseIioScanType("le:s64/64>>0"), ts), 0x0007060504030201);
}

TEST(ImuMounting, AxisRemapsBecomeTheSameRotation) {
  struct Case {
    const char* axes;
    std::array<double, 9> matrix;
  };
  const Case cases[] = {
      {"x,y,z", {1, 0, 0, 0, 1, 0, 0, 0, 1}},
      {"x,-y,-z", {1, 0, 0, 0, -1, 0, 0, 0, -1}},
      {"y,-x,z", {0, 1, 0, -1, 0, 0, 0, 0, 1}},
      {" -z , y , x ", {0, 0, -1, 0, 1, 0, 1, 0, 0}},  // pitch -90: gimbal lock
      {"z,y,-x", {0, 0, 1, 0, 1, 0, -1, 0, 0}},        // pitch +90
      {"z,x,y", {0, 0, 1, 1, 0, 0, 0, 1, 0}},
  };
  for (const Case& c : cases) {
    Result<ImuMounting> m = ImuMountingFromAxes(c.axes);
    ASSERT_TRUE(m.ok()) << c.axes << ": " << m.status().message();
    Result<std::array<double, 9>> r = ImuMountingMatrix(*m);
    ASSERT_TRUE(r.ok());
    for (std::size_t i = 0; i < 9; ++i)
      EXPECT_NEAR((*r)[i], c.matrix[i], 1e-12) << c.axes << " element " << i;
  }
  for (const char* bad : {"", "x,y", "x,x,z", "x,y,w", "x;y;z", "x,y,z,", "x,y,-z", "y,x,z"}) {
    Result<ImuMounting> m = ImuMountingFromAxes(bad);
    EXPECT_EQ(m.status().code(), StatusCode::kInvalidArgument) << "'" << bad << "'";
  }
  EXPECT_TRUE(Contains(ImuMountingFromAxes("x,y,-z").status(), "mirror"));
}

TEST(ImuMounting, AnglesFollowTheLensConvention) {
  // Rz(yaw) Ry(pitch) Rx(roll): pitch 90 takes IMU z to body x.
  Result<std::array<double, 9>> r = ImuMountingMatrix({0, 90, 0});
  ASSERT_TRUE(r.ok());
  EXPECT_EQ((*r)[2], 1.0);
  EXPECT_EQ((*r)[8], 0.0);
  EXPECT_EQ(ImuMountingMatrix({0, 0, INFINITY}).status().code(), StatusCode::kInvalidArgument);
}

// The driver pointed at a fake device's sysfs and /dev folders.
IioImuConfig FakeDeviceConfig(const FakeIioDevice& fake, const char* device = "fake_imu") {
  IioImuConfig c;
  std::snprintf(c.device, sizeof(c.device), "%s", device);
  std::snprintf(c.sysfs_root, sizeof(c.sysfs_root), "%s", fake.sysfs_root().c_str());
  std::snprintf(c.dev_root, sizeof(c.dev_root), "%s", fake.dev_root().c_str());
  return c;
}

class IioImuFake : public ::testing::Test {
 protected:
  IioImuConfig Config(const FakeIioDevice& fake, const char* device = "fake_imu") {
    IioImuConfig c = FakeDeviceConfig(fake, device);
    std::snprintf(c.trigger, sizeof(c.trigger), "faketrig");
    return c;
  }
  skyloc::testing::ScratchDir scratch_{"imu_iio_"};
};

TEST_F(IioImuFake, FindsTheDeviceByNameNodeOrSysfsName) {
  FakeIioDevice fake(scratch_.path(), {});
  for (std::string device : {std::string("fake_imu"), std::string("iio:device2"), fake.node()}) {
    IioImu imu(Config(fake, device.c_str()));
    Status s = imu.Open();
    EXPECT_TRUE(s.ok()) << device << ": " << s.message();
    EXPECT_TRUE(imu.buffered()) << imu.info().source;
  }
}

TEST_F(IioImuFake, AMissingDeviceIsOneErrorListingWhatIsThere) {
  FakeIioDevice fake(scratch_.path(), {});
  IioImu imu(Config(fake, "mpu6050"));
  Status s = imu.Open();
  EXPECT_EQ(s.code(), StatusCode::kNotFound);
  EXPECT_TRUE(Contains(s, "no IIO device named 'mpu6050'")) << s.message();
  EXPECT_TRUE(Contains(s, "present: fake_imu")) << s.message();
  IioImu by_number(Config(fake, "iio:device7"));
  s = by_number.Open();
  EXPECT_EQ(s.code(), StatusCode::kNotFound) << s.message();
  EXPECT_TRUE(Contains(s, "iio:device7")) << s.message();
}

TEST_F(IioImuFake, ADeviceWithoutAccelerometerOrScaleIsRefused) {
  FakeIioDevice fake(scratch_.path(), {});
  std::filesystem::remove(fake.dir() + "/in_accel_scale");
  IioImu no_scale(Config(fake));
  Status s = no_scale.Open();
  EXPECT_EQ(s.code(), StatusCode::kNotFound);
  EXPECT_TRUE(Contains(s, "in_accel_scale")) << s.message();
  std::filesystem::remove(fake.dir() + "/in_accel_z_raw");
  IioImu no_accel(Config(fake));
  s = no_accel.Open();
  EXPECT_EQ(s.code(), StatusCode::kNotFound);
  EXPECT_TRUE(Contains(s, "has no accelerometer")) << s.message();
  EXPECT_TRUE(Contains(s, "in_accel_z_raw")) << s.message();
}

TEST_F(IioImuFake, TurnsOffOtherChannelsAndSelectsTheMonotonicClock) {
  FakeIioDevice fake(scratch_.path(), {});
  IioImu imu(Config(fake));
  ASSERT_TRUE(imu.Open().ok());
  EXPECT_EQ(fake.Get("scan_elements/in_temp_en"), "0");
  EXPECT_EQ(fake.Get("scan_elements/in_accel_y_en"), "1");
  EXPECT_EQ(fake.Get("scan_elements/in_anglvel_z_en"), "1");
  EXPECT_EQ(fake.Get("scan_elements/in_timestamp_en"), "1");
  EXPECT_EQ(fake.Get("current_timestamp_clock"), "monotonic");
  EXPECT_EQ(fake.Get("trigger/current_trigger"), "faketrig");
  EXPECT_EQ(fake.Get("buffer/length"), "100");
  EXPECT_EQ(fake.Get("buffer/enable"), "0");
  ASSERT_TRUE(imu.Start().ok());
  EXPECT_EQ(fake.Get("buffer/enable"), "1");
  imu.Stop();
  EXPECT_EQ(fake.Get("buffer/enable"), "0");
}

TEST_F(IioImuFake, ConvertsRawWithOffsetAndPerAxisScale) {
  FakeIioDevice fake(scratch_.path(), {});
  fake.Put(fake.dir() + "/in_accel_x_scale", "0.002");  // per-axis wins over shared
  fake.Put(fake.dir() + "/in_anglvel_offset", "5");
  fake.accel_raw = {100, -200, 16399};
  IioImu imu(Config(fake));
  ASSERT_TRUE(imu.Open().ok());
  ASSERT_TRUE(imu.Start().ok());
  fake.Produce(1);
  std::array<dsp::ImuSample, 4> buf{};
  Result<std::size_t> n = imu.Read(buf, milliseconds(500));
  ASSERT_TRUE(n.ok()) << n.status().message();
  EXPECT_FLOAT_EQ(buf[0].accel_mps2[0], static_cast<float>(100 * 0.002));
  EXPECT_FLOAT_EQ(buf[0].accel_mps2[1], static_cast<float>(-200 * 0.000598));
  EXPECT_FLOAT_EQ(buf[0].gyro_radps[1], static_cast<float>((-20 + 5) * 0.001));
}

TEST_F(IioImuFake, WithoutATriggerAutoModeFallsBackToPollingAndSaysWhy) {
  FakeIioDevice fake(scratch_.path(), {});
  IioImuConfig c = Config(fake);
  c.trigger[0] = '\0';
  c.sample_rate_hz = 1000;
  IioImu imu(c);
  ASSERT_TRUE(imu.Open().ok());
  EXPECT_FALSE(imu.buffered());
  EXPECT_NE(std::string(imu.info().source).find("no trigger attached"), std::string::npos)
      << imu.info().source;
  ASSERT_TRUE(imu.Start().ok());
  std::array<dsp::ImuSample, 4> buf{};
  Result<std::size_t> n = imu.Read(buf, milliseconds(500));
  ASSERT_TRUE(n.ok()) << n.status().message();
  EXPECT_NEAR(buf[0].accel_mps2[2], 9.8066, 1e-3);
  imu.Close();

  c.mode = IioImuConfig::Mode::kBuffer;
  IioImu strict(c);
  Status s = strict.Open();
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  EXPECT_TRUE(Contains(s, "no trigger attached")) << s.message();
}

TEST_F(IioImuFake, AccelAndGyroOnTwoDevicesArePolled) {
  FakeIioDevice accel(scratch_.path(), {"fake_accel", 0, true, false});
  FakeIioDevice gyro(scratch_.path(), {"fake_gyro", 1, true, true});
  IioImuConfig c = Config(accel, "fake_accel");
  std::snprintf(c.gyro_device, sizeof(c.gyro_device), "fake_gyro");
  c.sample_rate_hz = 1000;
  IioImu imu(c);
  ASSERT_TRUE(imu.Open().ok());
  EXPECT_FALSE(imu.buffered());
  EXPECT_TRUE(imu.info().has_gyro);
  EXPECT_NE(std::string(imu.info().source).find("separate IIO devices"), std::string::npos);
  ASSERT_TRUE(imu.Start().ok());
  std::array<dsp::ImuSample, 4> buf{};
  Result<std::size_t> n = imu.Read(buf, milliseconds(500));
  ASSERT_TRUE(n.ok()) << n.status().message();
  EXPECT_FLOAT_EQ(buf[0].gyro_radps[2], static_cast<float>(30 * 0.001));

  IioImu accel_only(Config(accel, "fake_accel"));
  ASSERT_TRUE(accel_only.Open().ok());
  EXPECT_FALSE(accel_only.info().has_gyro);
  EXPECT_TRUE(accel_only.buffered());
}

TEST_F(IioImuFake, KernelFifoGapsAreCountedAsDropped) {
  FakeIioDevice fake(scratch_.path(), {});
  IioImu imu(Config(fake));
  ASSERT_TRUE(imu.Open().ok());
  ASSERT_TRUE(imu.Start().ok());
  std::array<dsp::ImuSample, 16> buf{};
  fake.Produce(2);
  ASSERT_TRUE(imu.Read(buf, milliseconds(100)).ok());
  EXPECT_EQ(imu.counters().dropped, 0u);
  // 5 periods (at 100 Hz) pass unread by the fake: the next scan comes 4 samples late.
  ::usleep(50'000);
  fake.Produce(1);
  ASSERT_TRUE(imu.Read(buf, milliseconds(100)).ok());
  EXPECT_GE(imu.counters().dropped, 3u);
}

// --- the simulated IMU ---
std::vector<dsp::ImuSample> Ramp(int n) {
  std::vector<dsp::ImuSample> v(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    v[static_cast<std::size_t>(i)].timestamp_ns = 5'000'000LL * i;  // 200 Hz
    v[static_cast<std::size_t>(i)].accel_mps2 = {static_cast<float>(i), 0, 9.8f};
  }
  return v;
}

TEST(SimulatedImu, ReplaysTheSamplesThenEnds) {
  const std::vector<dsp::ImuSample> samples = Ramp(10);
  SimulatedImu imu({}, samples);
  ASSERT_TRUE(imu.Open().ok());
  ASSERT_TRUE(imu.Start().ok());
  std::array<dsp::ImuSample, 4> buf{};
  float expected = 0;
  for (int call = 0; call < 3; ++call) {
    Result<std::size_t> n = imu.Read(buf, milliseconds(0));
    ASSERT_TRUE(n.ok());
    for (std::size_t i = 0; i < *n; ++i)
      EXPECT_EQ(buf[i].accel_mps2[0], expected++);
  }
  EXPECT_EQ(expected, 10.0f);
  EXPECT_EQ(imu.Read(buf, milliseconds(0)).status().code(), StatusCode::kOutOfRange);
}

TEST(SimulatedImu, PacedByTheClockAndStampedWithIt) {
  const std::vector<dsp::ImuSample> samples = Ramp(10);
  ManualClock clock(std::chrono::seconds(7));
  SimulatedImu imu({}, samples, &clock);
  ASSERT_TRUE(imu.Open().ok());
  ASSERT_TRUE(imu.Start().ok());
  std::array<dsp::ImuSample, 8> buf{};
  Result<std::size_t> n = imu.Read(buf, milliseconds(100));
  ASSERT_TRUE(n.ok());
  EXPECT_EQ(*n, 1u);  // only sample 0 is due
  EXPECT_EQ(buf[0].timestamp_ns, 7'000'000'000);
  EXPECT_EQ(imu.Read(buf, milliseconds(100)).status().code(), StatusCode::kDeadlineExceeded);
  clock.Advance(milliseconds(12));  // samples 1 and 2 (5 and 10 ms) are due
  n = imu.Read(buf, milliseconds(100));
  ASSERT_TRUE(n.ok());
  EXPECT_EQ(*n, 2u);
  EXPECT_EQ(buf[1].timestamp_ns, 7'010'000'000);
}

TEST(SimulatedImu, FaultsVanishStallDrop) {
  const std::vector<dsp::ImuSample> samples = Ramp(20);
  SimulatedImu imu({}, samples);
  ASSERT_TRUE(imu.InjectFault({ImuFault::Kind::kDrop, 2, 3}).ok());
  ASSERT_TRUE(imu.InjectFault({ImuFault::Kind::kStall, 8, 2}).ok());
  ASSERT_TRUE(imu.InjectFault({ImuFault::Kind::kVanish, 12, 1}).ok());
  ASSERT_TRUE(imu.Open().ok());
  ASSERT_TRUE(imu.Start().ok());
  std::array<dsp::ImuSample, 32> buf{};
  Result<std::size_t> n = imu.Read(buf, milliseconds(0));
  ASSERT_TRUE(n.ok());
  ASSERT_EQ(*n, 5u);  // 0, 1, 5, 6, 7
  EXPECT_EQ(buf[2].accel_mps2[0], 5.0f);
  EXPECT_EQ(imu.counters().dropped, 3u);
  EXPECT_EQ(imu.Read(buf, milliseconds(0)).status().code(), StatusCode::kDeadlineExceeded);
  EXPECT_EQ(imu.Read(buf, milliseconds(0)).status().code(), StatusCode::kDeadlineExceeded);
  n = imu.Read(buf, milliseconds(0));
  ASSERT_TRUE(n.ok());
  EXPECT_EQ(*n, 4u);  // 8..11
  EXPECT_EQ(imu.Read(buf, milliseconds(0)).status().code(), StatusCode::kUnavailable);
  EXPECT_EQ(imu.Read(buf, milliseconds(0)).status().code(), StatusCode::kUnavailable);
  EXPECT_EQ(imu.counters().errors, 2u);  // the two kUnavailable; stalls are time-outs
  EXPECT_EQ(imu.counters().outages, 1u);
  imu.Close();
  // Still unplugged: Open() fails as the IIO driver's does, until the device is back.
  EXPECT_EQ(imu.Open().code(), StatusCode::kUnavailable);
  imu.ClearFaults();
  ASSERT_TRUE(imu.Open().ok());
  ASSERT_TRUE(imu.Start().ok());
  n = imu.Read(buf, milliseconds(0));
  ASSERT_TRUE(n.ok());
  EXPECT_EQ(*n, 8u);  // 12..19: a replugged device goes on where it was
  EXPECT_EQ(buf[0].accel_mps2[0], 12.0f);
  // A plain Close() and Open() replays from the start, where the drop fires again.
  imu.Close();
  ASSERT_TRUE(imu.InjectFault({ImuFault::Kind::kDrop, 2, 3}).ok());
  ASSERT_TRUE(imu.Open().ok());
  ASSERT_TRUE(imu.Start().ok());
  n = imu.Read(buf, milliseconds(0));
  ASSERT_TRUE(n.ok());
  EXPECT_EQ(*n, 17u);
}

// The IIO driver's time is its Clock: under a ManualClock, polled samples are stamped with
// the clock's time, ticks the reader missed are counted as dropped, and a device that goes
// away is reopened on the backoff schedule of the V4L2 camera (StreamRecovery's defaults:
// 100 ms, then 200 ms, ...), all without waiting.
TEST(IioImu, PollingTimingOutagesAndReopensFollowTheClock) {
  const skyloc::testing::ScratchDir scratch("imu_iio_clock_");
  FakeIioDevice fake(scratch.path(), FakeIioDevice::Options{"fake_imu", 2, false, true});
  IioImuConfig c = FakeDeviceConfig(fake);
  c.sample_rate_hz = 100.0;  // a tick every 10 ms
  c.mode = IioImuConfig::Mode::kPolling;
  ManualClock clock(std::chrono::seconds(1000));
  IioImu imu(c, &clock);
  ASSERT_TRUE(imu.Open().ok());
  ASSERT_TRUE(imu.Start().ok());
  std::array<dsp::ImuSample, 4> buf{};
  const std::int64_t t0 = 1'000'000'000'000;
  Result<std::size_t> n = imu.Read(buf, milliseconds(0));  // the first tick is due at Start()
  ASSERT_TRUE(n.ok()) << n.status().message();
  EXPECT_EQ(buf[0].timestamp_ns, t0);
  // The next tick is 10 ms away, and the clock has not moved: nothing yet.
  EXPECT_EQ(imu.Read(buf, milliseconds(0)).status().code(), StatusCode::kDeadlineExceeded);
  clock.Advance(milliseconds(10));
  n = imu.Read(buf, milliseconds(0));
  ASSERT_TRUE(n.ok()) << n.status().message();
  EXPECT_EQ(buf[0].timestamp_ns, t0 + 10'000'000);
  clock.Advance(milliseconds(40));  // three ticks pass unread
  n = imu.Read(buf, milliseconds(0));
  ASSERT_TRUE(n.ok());
  EXPECT_EQ(buf[0].timestamp_ns, t0 + 50'000'000);
  EXPECT_EQ(imu.counters().dropped, 3u);
  EXPECT_EQ(imu.counters().samples, 3u);

  // Unplugged: found at the next read, closed, counted; the first reopen is due 100 ms later.
  fake.Vanish();
  clock.Advance(milliseconds(10));
  Status s = imu.Read(buf, milliseconds(0)).status();
  EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.message();
  EXPECT_EQ(imu.counters().outages, 1u);
  EXPECT_EQ(imu.recovery().state(), StreamRecovery::State::kBackingOff);
  EXPECT_EQ(imu.recovery().next_attempt(), Nanoseconds(t0 + 160'000'000));
  clock.Advance(milliseconds(99));
  EXPECT_EQ(imu.Read(buf, milliseconds(0)).status().code(), StatusCode::kUnavailable);
  EXPECT_EQ(imu.recovery().consecutive_failures(), 0u) << "no attempt before the backoff";
  clock.Advance(milliseconds(1));  // due: the attempt fails (still gone), the next in 200 ms
  s = imu.Read(buf, milliseconds(0)).status();
  EXPECT_EQ(s.code(), StatusCode::kUnavailable);
  EXPECT_NE(std::string(s.message()).find("reopen 1 failed"), std::string::npos) << s.message();
  EXPECT_EQ(imu.recovery().next_attempt(), Nanoseconds(t0 + 360'000'000));

  // Plugged back: the next attempt on schedule reopens it and samples flow again.
  fake.Revive();
  clock.Advance(milliseconds(199));
  EXPECT_EQ(imu.Read(buf, milliseconds(0)).status().code(), StatusCode::kUnavailable);
  EXPECT_EQ(imu.counters().reopens, 0u);
  clock.Advance(milliseconds(1));
  n = imu.Read(buf, milliseconds(0));
  ASSERT_TRUE(n.ok()) << n.status().message();
  EXPECT_EQ(buf[0].timestamp_ns, t0 + 360'000'000);
  EXPECT_EQ(imu.counters().reopens, 1u);
  EXPECT_EQ(imu.counters().outages, 1u);
  EXPECT_EQ(imu.recovery().state(), StreamRecovery::State::kStreaming);
}

// However long the IMU was gone, it is back in use within a second of its return (frames are
// described as if level until then): the reopen attempts never drift further apart than
// that. Read every 10 ms, as a 100 fps frame loop asks for the attitude.
TEST(IioImu, AnImuBackAfterAnyOutageIsReopenedWithinASecond) {
  for (const int outage_ms : {2000, 2900, 10'000, 60'000}) {
    SCOPED_TRACE(outage_ms);
    const skyloc::testing::ScratchDir scratch("imu_iio_back_");
    FakeIioDevice fake(scratch.path(), FakeIioDevice::Options{"fake_imu", 2, false, true});
    IioImuConfig c = FakeDeviceConfig(fake);
    c.sample_rate_hz = 100.0;
    c.mode = IioImuConfig::Mode::kPolling;
    ManualClock clock(std::chrono::seconds(1000));
    IioImu imu(c, &clock);
    ASSERT_TRUE(imu.Open().ok());
    ASSERT_TRUE(imu.Start().ok());
    std::array<dsp::ImuSample, 4> buf{};
    ASSERT_TRUE(imu.Read(buf, milliseconds(0)).ok());

    fake.Vanish();
    for (int t = 0; t < outage_ms; t += 10) {
      clock.Advance(milliseconds(10));
      ASSERT_FALSE(imu.Read(buf, milliseconds(0)).ok());
    }
    ASSERT_EQ(imu.counters().outages, 1u);
    fake.Revive();
    int back_after_ms = 0;
    while (!imu.Read(buf, milliseconds(0)).ok() && back_after_ms <= 5000) {
      clock.Advance(milliseconds(10));
      back_after_ms += 10;
    }
    EXPECT_LE(back_after_ms, 1000);
    EXPECT_EQ(imu.counters().reopens, 1u);
  }
}

TEST(SimulatedImu, RefusesSamplesOutOfOrder) {
  std::vector<dsp::ImuSample> samples = Ramp(3);
  samples[2].timestamp_ns = samples[1].timestamp_ns;
  SimulatedImu imu({}, samples);
  Status s = imu.Open();
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(Contains(s, "strictly increase")) << s.message();
  SimulatedImu empty({}, std::span<const dsp::ImuSample>());
  EXPECT_EQ(empty.Open().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace skyloc::drivers
