// One suite for every AttitudeSource: the attitude recorded with the frames (datasets) and
// an IMU through the attitude filter (here the simulated IMU; the IIO driver is the same
// ImuAttitudeSource over another ImuDevice, whose own compliance suite runs on the kernel's
// iio_dummy in the HIL VM). Each instance is a robot standing still at a known tilt; the
// reference is the closed form dsp::UpFromRollPitch.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "skyloc/drivers/attitude_source.h"
#include "skyloc/drivers/simulated_imu.h"
#include "skyloc/platform/alloc_counter.h"

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
  // A frame at time t (ns). `recorded` false: a frame that came without an attitude.
  virtual Frame MakeFrame(std::int64_t t_ns, bool recorded = true) {
    Frame f;
    f.timestamp = Nanoseconds{t_ns};
    f.sequence = static_cast<std::uint64_t>(t_ns / 100'000'000);
    (void)recorded;
    return f;
  }
  // The time before which the source cannot know anything.
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

using Factory = std::unique_ptr<Instance> (*)();

struct Param {
  const char* name;
  Factory make;
};

class AttitudeSourceSuite : public ::testing::TestWithParam<Param> {
 protected:
  void SetUp() override { instance_ = GetParam().make(); }
  std::unique_ptr<Instance> instance_;
};

double AngleDeg(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  const double dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  return std::acos(std::min(1.0, std::max(-1.0, dot))) * 180.0 / 3.14159265358979323846;
}

TEST_P(AttitudeSourceSuite, AStillTiltedRobotReadsItsTiltAtEveryFrame) {
  AttitudeSource& source = instance_->source();
  ASSERT_TRUE(source.Open().ok());
  const std::array<double, 3> truth = dsp::UpFromRollPitch(kRollDeg, kPitchDeg);
  // The IMU's gyro bias |b| = 0.0023 rad/s tilts a Mahony filter's estimate by at most
  // asin(|b| / kp) = 0.13 degrees (kp = 1/s) while its integral term learns the bias.
  const double tolerance_deg = std::asin(0.0023 / dsp::AttitudeFilterParams{}.kp) * 57.3 + 0.01;
  for (std::int64_t t = instance_->first_known_ns();
       t < instance_->first_known_ns() + 9'000'000'000; t += 100'000'000) {
    Result<dsp::Attitude> a = source.At(instance_->MakeFrame(t));
    ASSERT_TRUE(a.ok()) << t << ": " << a.status().message();
    EXPECT_LE(a->timestamp_ns, t);  // never an estimate from after the frame
    EXPECT_LT(AngleDeg(a->up, truth), tolerance_deg) << t;
    EXPECT_NEAR(a->roll_deg, kRollDeg, 2 * tolerance_deg);
    EXPECT_NEAR(a->pitch_deg, kPitchDeg, tolerance_deg);
  }
  EXPECT_EQ(source.counters().estimates, 90u);
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
  EXPECT_TRUE(source.At(instance_->MakeFrame(instance_->first_known_ns() + 1'000'000)).ok());
  EXPECT_EQ(source.counters().estimates, 1u);
  source.Close();
}

TEST_P(AttitudeSourceSuite, AtAllocatesNothing) {
  ASSERT_TRUE(AllocationCounterActive());
  AttitudeSource& source = instance_->source();
  ASSERT_TRUE(source.Open().ok());
  std::vector<Frame> frames;
  for (std::int64_t t = instance_->first_known_ns();
       t < instance_->first_known_ns() + 9'000'000'000; t += 33'333'333)
    frames.push_back(instance_->MakeFrame(t));
  AllocationScope scope;
  for (const Frame& f : frames)
    ASSERT_TRUE(source.At(f).ok());
  EXPECT_EQ(scope.allocations(), 0u);
  source.Close();
}

INSTANTIATE_TEST_SUITE_P(
    All, AttitudeSourceSuite,
    ::testing::Values(Param{"RecordedFrames",
                            [] { return std::unique_ptr<Instance>(new RecordedFrames); }},
                      Param{"SimulatedImuFiltered",
                            [] { return std::unique_ptr<Instance>(new SimulatedImuFiltered); }}),
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

}  // namespace
}  // namespace skyloc::drivers
