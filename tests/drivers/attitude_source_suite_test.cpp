// One suite for every AttitudeSource: the attitude recorded with the frames (datasets), an
// IMU through the attitude filter on the simulated IMU, and the same on the IIO driver over
// a real device named by SKYLOC_TEST_IIO_DEVICE (the HIL VM's iio_dummy, a still and level
// IMU: SKIPPED with the reason elsewhere). Each instance is a robot standing still at a
// known attitude; the reference is the closed form dsp::UpFromRollPitch.
#include <gtest/gtest.h>
#include <time.h>

#include <cmath>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "skyloc/drivers/attitude_source.h"
#include "skyloc/drivers/iio_imu.h"
#include "skyloc/drivers/simulated_imu.h"
#include "skyloc/platform/alloc_counter.h"
#include "skyloc/platform/clock.h"
#include "test_env.h"

namespace skyloc::drivers {
namespace {

constexpr double kRollDeg = 20.0;
constexpr double kPitchDeg = -35.0;
constexpr std::int64_t kSamplePeriodNs = 5'000'000;  // 200 Hz
constexpr std::int64_t kSamples = 2000;              // 10 s

// A source and how frames reach it.
struct Instance {
  virtual ~Instance() = default;
  virtual AttitudeSource& source() = 0;
  // The robot's true attitude and the IMU's gyro bias (which bounds the filter's error).
  virtual std::array<double, 2> roll_pitch_deg() const { return {kRollDeg, kPitchDeg}; }
  virtual double gyro_bias_radps() const { return 0.0023; }
  // How long the tilt case follows the robot, and a wait until the source can know time
  // t (a real device delivers samples in real time; the others have them at once).
  virtual std::int64_t span_ns() const { return 9'000'000'000; }
  virtual void WaitUntil(std::int64_t t_ns) { (void)t_ns; }
  std::string skip;  // non-empty: no such device here, and why
  // A frame at time t (ns). `recorded` false: a frame that came without an attitude.
  virtual Frame MakeFrame(std::int64_t t_ns, bool recorded = true) {
    Frame f;
    f.timestamp = Nanoseconds{t_ns};
    f.sequence = static_cast<std::uint64_t>(t_ns / 100'000'000);
    (void)recorded;
    return f;
  }
  // The time before which the source cannot know anything (after Open()).
  virtual std::int64_t first_known_ns() const = 0;
};

struct RecordedFrames final : Instance {
  FrameAttitudeSource frames;
  AttitudeSource& source() override { return frames; }
  Frame MakeFrame(std::int64_t t_ns, bool recorded) override {
    Frame f = Instance::MakeFrame(t_ns);
    if (recorded && t_ns >= first_known_ns())
      f.attitude = dsp::AttitudeFromRollPitch(t_ns, kRollDeg, kPitchDeg);
    return f;
  }
  std::int64_t first_known_ns() const override { return 0; }
};

struct SimulatedImuFiltered final : Instance {
  std::vector<dsp::ImuSample> samples;
  std::unique_ptr<SimulatedImu> imu;
  std::unique_ptr<ImuAttitudeSource> filtered;
  SimulatedImuFiltered() {
    const std::array<double, 3> up = dsp::UpFromRollPitch(kRollDeg, kPitchDeg);
    for (std::int64_t i = 0; i < kSamples; ++i) {
      dsp::ImuSample s;
      s.timestamp_ns = first_known_ns() + i * kSamplePeriodNs;
      for (int k = 0; k < 3; ++k)
        s.accel_mps2[static_cast<std::size_t>(k)] =
            static_cast<float>(dsp::kStandardGravity * up[static_cast<std::size_t>(k)]);
      s.gyro_radps = {0.001f, -0.002f, 0.0005f};
      samples.push_back(s);
    }
    imu = std::make_unique<SimulatedImu>(SimulatedImuConfig{}, samples);
    filtered = std::make_unique<ImuAttitudeSource>(imu.get(), ImuAttitudeConfig{});
  }
  AttitudeSource& source() override { return *filtered; }
  std::int64_t first_known_ns() const override { return 1'000'000'000; }
};

std::int64_t MonotonicNs() {
  timespec t{};
  ::clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
}

// The IIO driver on a real IMU, buffered (the HIL VM's iio_dummy: still and level, gyro
// raw (10, -20, 30) x 0.001 rad/s). Frames are stamped with CLOCK_MONOTONIC, as the
// camera drivers stamp theirs, and the case waits for real time to pass.
struct IioFiltered final : Instance {
  std::unique_ptr<IioImu> imu;
  std::unique_ptr<ImuAttitudeSource> filtered;
  mutable std::int64_t t0 = 0;
  IioFiltered() {
    const char* device = testing::Env("SKYLOC_TEST_IIO_DEVICE");
    if (device == nullptr) {
      skip =
          "no IIO IMU: set SKYLOC_TEST_IIO_DEVICE (the HIL VM does, with iio_dummy) and "
          "SKYLOC_TEST_IIO_TRIGGER";
      return;
    }
    IioImuConfig c;
    std::snprintf(c.device, sizeof c.device, "%s", device);
    if (const char* trigger = testing::Env("SKYLOC_TEST_IIO_TRIGGER"))
      std::snprintf(c.trigger, sizeof c.trigger, "%s", trigger);
    c.sample_rate_hz = 100.0;
    imu = std::make_unique<IioImu>(c);
    filtered = std::make_unique<ImuAttitudeSource>(imu.get(), ImuAttitudeConfig{});
  }
  AttitudeSource& source() override { return *filtered; }
  std::array<double, 2> roll_pitch_deg() const override { return {0.0, 0.0}; }
  double gyro_bias_radps() const override { return std::hypot(0.010, 0.020); }
  std::int64_t span_ns() const override { return 1'500'000'000; }
  // Samples begin when the source opens; the first frame it can know comes 300 ms later.
  std::int64_t first_known_ns() const override {
    if (t0 == 0)
      t0 = MonotonicNs() + 300'000'000;
    return t0;
  }
  void WaitUntil(std::int64_t t_ns) override {
    // The sample stamped t is in the kernel's buffer a trigger period or two later.
    const std::int64_t due = t_ns + 50'000'000;
    const std::int64_t now = MonotonicNs();
    if (due > now)
      std::this_thread::sleep_for(std::chrono::nanoseconds(due - now));
  }
};

using Factory = std::unique_ptr<Instance> (*)();

struct Param {
  const char* name;
  Factory make;
};

class AttitudeSourceSuite : public ::testing::TestWithParam<Param> {
 protected:
  void SetUp() override {
    instance_ = GetParam().make();
    if (!instance_->skip.empty())
      GTEST_SKIP() << instance_->skip;
  }
  std::unique_ptr<Instance> instance_;
};

double AngleDeg(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  const double dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  return std::acos(std::min(1.0, std::max(-1.0, dot))) * 180.0 / 3.14159265358979323846;
}

TEST_P(AttitudeSourceSuite, AStillTiltedRobotReadsItsTiltAtEveryFrame) {
  AttitudeSource& source = instance_->source();
  ASSERT_TRUE(source.Open().ok());
  const auto [roll, pitch] = instance_->roll_pitch_deg();
  const std::array<double, 3> truth = dsp::UpFromRollPitch(roll, pitch);
  // A gyro bias |b| (its horizontal part) tilts a Mahony filter's estimate by at most
  // asin(|b| / kp) (kp = 1/s) while the integral term learns it: 0.13 degrees for the
  // simulated IMU's bias, 1.3 for iio_dummy's.
  const double tolerance_deg =
      std::asin(instance_->gyro_bias_radps() / dsp::AttitudeFilterParams{}.kp) * 57.3 + 0.01;
  const std::int64_t first = instance_->first_known_ns();
  std::uint64_t frames = 0;
  for (std::int64_t t = first; t < first + instance_->span_ns(); t += 100'000'000) {
    instance_->WaitUntil(t);
    Result<dsp::Attitude> a = source.At(instance_->MakeFrame(t));
    ++frames;
    ASSERT_TRUE(a.ok()) << t << ": " << a.status().message();
    EXPECT_LE(a->timestamp_ns, t);  // never an estimate from after the frame
    EXPECT_LT(AngleDeg(a->up, truth), tolerance_deg) << t;
    EXPECT_NEAR(a->roll_deg, roll, 2 * tolerance_deg);
    EXPECT_NEAR(a->pitch_deg, pitch, tolerance_deg);
  }
  EXPECT_EQ(source.counters().estimates, frames);
  EXPECT_EQ(source.counters().missing, 0u);
  source.Close();
}

TEST_P(AttitudeSourceSuite, AtBeforeOpenIsRefused) {
  AttitudeSource& source = instance_->source();
  EXPECT_EQ(source.At(instance_->MakeFrame(instance_->first_known_ns())).status().code(),
            StatusCode::kFailedPrecondition);
  ASSERT_TRUE(source.Open().ok());
  EXPECT_EQ(source.Open().code(), StatusCode::kFailedPrecondition);
  source.Close();
  source.Close();  // idempotent
}

TEST_P(AttitudeSourceSuite, AFrameTheSourceKnowsNothingOfIsNotFoundAndCounted) {
  AttitudeSource& source = instance_->source();
  ASSERT_TRUE(source.Open().ok());
  // Before the first sample (or a frame recorded without its attitude).
  const Frame early = instance_->MakeFrame(instance_->first_known_ns() - 500'000'000, false);
  EXPECT_EQ(source.At(early).status().code(), StatusCode::kNotFound);
  EXPECT_EQ(source.counters().missing, 1u);
  instance_->WaitUntil(instance_->first_known_ns() + 1'000'000);
  EXPECT_TRUE(source.At(instance_->MakeFrame(instance_->first_known_ns() + 1'000'000)).ok());
  EXPECT_EQ(source.counters().estimates, 1u);
  source.Close();
}

TEST_P(AttitudeSourceSuite, AtAllocatesNothing) {
  ASSERT_TRUE(AllocationCounterActive());
  AttitudeSource& source = instance_->source();
  ASSERT_TRUE(source.Open().ok());
  std::vector<Frame> frames;
  const std::int64_t first = instance_->first_known_ns();
  for (std::int64_t t = first; t < first + instance_->span_ns(); t += 33'333'333)
    frames.push_back(instance_->MakeFrame(t));
  AllocationScope scope;
  for (const Frame& f : frames) {
    instance_->WaitUntil(f.timestamp.count());
    ASSERT_TRUE(source.At(f).ok());
  }
  EXPECT_EQ(scope.allocations(), 0u);
  source.Close();
}

INSTANTIATE_TEST_SUITE_P(
    All, AttitudeSourceSuite,
    ::testing::Values(Param{"RecordedFrames",
                            [] { return std::unique_ptr<Instance>(new RecordedFrames); }},
                      Param{"SimulatedImuFiltered",
                            [] { return std::unique_ptr<Instance>(new SimulatedImuFiltered); }},
                      Param{"Iio", [] { return std::unique_ptr<Instance>(new IioFiltered); }}),
    [](const ::testing::TestParamInfo<Param>& p) { return std::string(p.param.name); });

// The IMU's own failure modes, which a recorded attitude does not have.
TEST(ImuAttitudeSource, AnImuThatStopsGoesStaleAndAGoneImuIsUnavailable) {
  std::vector<dsp::ImuSample> samples(400);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    samples[i].timestamp_ns = static_cast<std::int64_t>(i) * kSamplePeriodNs;
    samples[i].accel_mps2 = {0.0f, 0.0f, static_cast<float>(dsp::kStandardGravity)};
  }
  {
    // The samples end at 2 s: a frame 100 ms later is fine, 300 ms later is stale.
    SimulatedImu imu({}, samples);
    ImuAttitudeSource source(&imu, {});
    ASSERT_TRUE(source.Open().ok());
    Frame f;
    f.timestamp = Nanoseconds{2'095'000'000};
    EXPECT_TRUE(source.At(f).ok());
    f.timestamp = Nanoseconds{2'300'000'000};
    const Status stale = source.At(f).status();
    EXPECT_EQ(stale.code(), StatusCode::kNotFound);
    EXPECT_NE(std::string(stale.message()).find("stale"), std::string::npos) << stale.message();
  }
  {
    SimulatedImu imu({}, samples);
    ASSERT_TRUE(imu.InjectFault({ImuFault::Kind::kVanish, 100, 1}).ok());
    ImuAttitudeSource source(&imu, {});
    ASSERT_TRUE(source.Open().ok());
    Frame f;
    f.timestamp = Nanoseconds{400'000'000};  // sample 80
    EXPECT_TRUE(source.At(f).ok());
    f.timestamp = Nanoseconds{1'000'000'000};  // past sample 100: the IMU is gone
    EXPECT_EQ(source.At(f).status().code(), StatusCode::kUnavailable);
    EXPECT_EQ(source.At(f).status().code(), StatusCode::kUnavailable);
    EXPECT_EQ(source.counters().unavailable, 2u);
  }
}

// An IMU unplugged mid-run and plugged back heals by itself, on the V4L2 camera's backoff
// capped at 500 ms (ImuRecoveryConfig: 100, 200, 400, 500 ms between attempts), and the
// frames get their attitude (so the gravity-aligned cap) back. All on a ManualClock: the
// simulated IMU is paced by it and the frames are stamped with it.
TEST(ImuAttitudeSource, AnUnpluggedImuReopensWithTheCameraBackoffAndTheAttitudeReturns) {
  const std::array<double, 3> up = dsp::UpFromRollPitch(kRollDeg, kPitchDeg);
  std::vector<dsp::ImuSample> samples(static_cast<std::size_t>(kSamples));
  for (std::size_t i = 0; i < samples.size(); ++i) {
    samples[i].timestamp_ns = static_cast<std::int64_t>(i) * kSamplePeriodNs;
    for (std::size_t k = 0; k < 3; ++k)
      samples[i].accel_mps2[k] = static_cast<float>(dsp::kStandardGravity * up[k]);
  }
  ManualClock clock(std::chrono::seconds(100));
  const std::int64_t t0 = clock.Now().count();
  SimulatedImu imu({}, samples, &clock);
  // Sample 400 is due 2 s after the start: the IMU is unplugged there.
  ASSERT_TRUE(imu.InjectFault({ImuFault::Kind::kVanish, 400, 1}).ok());
  ImuAttitudeSource source(&imu, {});
  ASSERT_TRUE(source.Open().ok());
  // The device is lost at the frame of 2.0 s; attempts at 2.1, 2.3 and 2.7 s find it still
  // unplugged (plugged back at 3.0 s), the one at 3.2 s reopens it. The frame at 3.2 s
  // has only the first sample after the gap, on which the filter restarts.
  constexpr std::int64_t kLost = 2'000'000'000, kReplug = 3'000'000'000, kReopen = 3'200'000'000;
  std::int64_t first_back = -1;
  for (std::int64_t t = 0; t <= 6'000'000'000; t += 100'000'000) {
    if (t == kReplug)
      imu.ClearFaults();
    clock.Set(Nanoseconds(t0 + t));
    Frame f;
    f.timestamp = clock.Now();
    f.sequence = static_cast<std::uint64_t>(t / 100'000'000);
    Result<dsp::Attitude> a = source.At(f);
    if (t < kLost || (first_back >= 0 && t > first_back)) {
      ASSERT_TRUE(a.ok()) << t << ": " << a.status().message();
      EXPECT_NEAR(a->roll_deg, kRollDeg, 0.5) << t;
      EXPECT_NEAR(a->pitch_deg, kPitchDeg, 0.5) << t;
    } else if (t < kReopen) {
      EXPECT_EQ(a.status().code(), StatusCode::kUnavailable) << t << ": " << a.status().message();
      EXPECT_EQ(imu.counters().reopens, 0u) << t;
    } else if (a.ok() && first_back < 0) {
      first_back = t;
    }
  }
  EXPECT_GE(first_back, kReopen);
  EXPECT_LE(first_back, kReopen + 100'000'000);
  EXPECT_EQ(imu.counters().outages, 1u);
  EXPECT_EQ(imu.counters().reopens, 1u);
  EXPECT_EQ(source.counters().unavailable, 12u);  // 2.0 .. 3.1 s
}

}  // namespace
}  // namespace skyloc::drivers
