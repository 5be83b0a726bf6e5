// The attitude filter against closed forms (docs/ATTITUDE.md, "What the tests prove").
#include "skyloc/dsp/attitude_filter.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "skyloc/platform/alloc_counter.h"
#include "support/angles.h"

namespace skyloc::dsp {
namespace {

constexpr double kG = kStandardGravity;
constexpr std::int64_t kStepNs = 5'000'000;  // 200 Hz

ImuSample Sample(std::int64_t t_ns, const std::array<double, 3>& accel,
                 const std::array<double, 3>& gyro = {0, 0, 0}) {
  ImuSample s;
  s.timestamp_ns = t_ns;
  for (std::size_t i = 0; i < 3; ++i) {
    s.accel_mps2[i] = static_cast<float>(accel[i]);
    s.gyro_radps[i] = static_cast<float>(gyro[i]);
  }
  return s;
}

std::array<double, 3> Scaled(const std::array<double, 3>& v, double k) {
  return {v[0] * k, v[1] * k, v[2] * k};
}

// The angle between two unit vectors, robust near 0.
double AngleBetween(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  const std::array<double, 3> c{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                                a[0] * b[1] - a[1] * b[0]};
  return std::atan2(std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]),
                    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]);
}

// Feeds `n` samples after *t (advancing it by kStepNs each).
void Feed(AttitudeFilter& f, std::int64_t* t, int n, const std::array<double, 3>& accel,
          const std::array<double, 3>& gyro = {0, 0, 0}) {
  for (int i = 0; i < n; ++i) {
    *t += kStepNs;
    ASSERT_EQ(f.Update(Sample(*t, accel, gyro)), AttitudeError::kOk);
  }
}

AttitudeFilterParams OneSampleInit() {
  AttitudeFilterParams p;
  p.init_samples = 1;
  return p;
}

TEST(AttitudeFilter, RefusesBadParametersAndUseBeforeInit) {
  AttitudeFilter f;
  EXPECT_EQ(f.Update(Sample(0, {0, 0, kG})), AttitudeError::kNotInitialised);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto check = [&](auto mutate, AttitudeError want) {
    AttitudeFilterParams p;
    mutate(p);
    EXPECT_EQ(ValidateAttitudeFilterParams(p), want);
    EXPECT_EQ(f.Init(p), want);
    EXPECT_EQ(f.Update(Sample(0, {0, 0, kG})), AttitudeError::kNotInitialised);
  };
  check([](AttitudeFilterParams& p) { p.kp = -1; }, AttitudeError::kBadGain);
  check([&](AttitudeFilterParams& p) { p.kp = nan; }, AttitudeError::kBadGain);
  check([](AttitudeFilterParams& p) { p.ki = -0.1; }, AttitudeError::kBadIntegralGain);
  check([](AttitudeFilterParams& p) { p.accel_gate_mps2 = 0; }, AttitudeError::kBadGate);
  check([](AttitudeFilterParams& p) { p.gravity_mps2 = 1.62; }, AttitudeError::kBadGravity);
  check([](AttitudeFilterParams& p) { p.max_gap_s = 0; }, AttitudeError::kBadMaxGap);
  check([](AttitudeFilterParams& p) { p.init_samples = 0; }, AttitudeError::kBadInitSamples);
  check([&](AttitudeFilterParams& p) { p.max_bias_radps = nan; }, AttitudeError::kBadMaxBias);
  EXPECT_EQ(f.Init(AttitudeFilterParams{}), AttitudeError::kOk);
  for (int e = 0; e <= static_cast<int>(AttitudeError::kNoGravity); ++e)
    EXPECT_GT(std::string(AttitudeErrorMessage(static_cast<AttitudeError>(e))).size(), 1u);
}

TEST(AttitudeFilter, FirstSampleGivesTheExactAttitude) {
  for (const double roll : {-60.0, -30.0, 0.0, 25.0, 60.0}) {
    for (const double pitch : {-60.0, -10.0, 0.0, 45.0, 60.0}) {
      AttitudeFilter f;
      ASSERT_EQ(f.Init(AttitudeFilterParams{}), AttitudeError::kOk);
      EXPECT_FALSE(f.has_estimate());
      ASSERT_EQ(f.Update(Sample(7, Scaled(UpFromRollPitch(roll, pitch), kG))), AttitudeError::kOk);
      ASSERT_TRUE(f.has_estimate());
      // The float sample rounds g * up to 2^-24 relative: 1e-5 deg.
      EXPECT_NEAR(f.attitude().roll_deg, roll, 1e-5);
      EXPECT_NEAR(f.attitude().pitch_deg, pitch, 1e-5);
      EXPECT_EQ(f.attitude().timestamp_ns, 7);
    }
  }
}

TEST(AttitudeFilter, InitialisationAveragesTheFirstSamples) {
  AttitudeFilterParams p;
  p.init_samples = 2;
  AttitudeFilter f;
  ASSERT_EQ(f.Init(p), AttitudeError::kOk);
  ASSERT_EQ(f.Update(Sample(0, {1, 0, kG})), AttitudeError::kOk);
  ASSERT_EQ(f.Update(Sample(kStepNs, {-1, 2, kG})), AttitudeError::kOk);
  EXPECT_TRUE(f.converging());
  const Attitude want = AttitudeFromUp(0, {0, 2, 2 * kG});
  EXPECT_NEAR(f.attitude().roll_deg, want.roll_deg, 1e-5);  // g as a float
  EXPECT_NEAR(f.attitude().pitch_deg, want.pitch_deg, 1e-5);
  EXPECT_GT(want.roll_deg, 5.8);
}

// Starting level, a constant tilt with ki = 0: the angle alpha between the estimate and
// the truth obeys d(alpha)/dt = -kp sin(alpha): tan(alpha/2) = tan(alpha0/2) exp(-kp t).
// Then with the default ki the estimate ends exactly on the tilt.
TEST(AttitudeFilter, StaticTiltConvergesAsTheClosedFormToTheExactAngles) {
  for (const double roll : {-60.0, 0.0, 20.0, 60.0}) {
    for (const double pitch : {-60.0, 0.0, 35.0, 60.0}) {
      const std::array<double, 3> up = UpFromRollPitch(roll, pitch);
      AttitudeFilterParams p = OneSampleInit();
      p.ki = 0;
      AttitudeFilter f;
      ASSERT_EQ(f.Init(p), AttitudeError::kOk);
      std::int64_t t = 0;
      ASSERT_EQ(f.Update(Sample(t, {0, 0, kG})), AttitudeError::kOk);
      const double alpha0 = AngleBetween(up, {0, 0, 1});
      double worst = 0;
      for (int second = 1; second <= 10; ++second) {
        Feed(f, &t, 200, Scaled(up, kG));
        const double want = 2 * std::atan(std::tan(alpha0 / 2) * std::exp(-p.kp * second));
        worst = std::max(worst, std::abs(AngleBetween(up, f.up()) - want));
      }
      // The step applies the correction of its start (an Euler step in alpha): it trails
      // the continuous solution by O(kp dt) of the distance left: 0.046 deg at most here.
      EXPECT_LT(worst, 0.06 * kDeg) << roll << " " << pitch;
      Feed(f, &t, 200 * 50, Scaled(up, kG));  // 60 s: e^-30 of the start
      EXPECT_NEAR(f.attitude().roll_deg, roll, 1e-5);
      EXPECT_NEAR(f.attitude().pitch_deg, pitch, 1e-5);

      // Defaults (ki on, init averaging): the same end point.
      AttitudeFilter d;
      ASSERT_EQ(d.Init(AttitudeFilterParams{}), AttitudeError::kOk);
      t = 0;
      ASSERT_EQ(d.Update(Sample(t, {0, 0, kG})), AttitudeError::kOk);
      Feed(d, &t, 9, {0, 0, kG});
      Feed(d, &t, 200 * 600, Scaled(up, kG));
      EXPECT_NEAR(d.attitude().roll_deg, roll, 1e-5) << pitch;
      EXPECT_NEAR(d.attitude().pitch_deg, pitch, 1e-5) << roll;
    }
  }
}

// With the accelerometer off (reading 0: weight 0) the gyro alone turns the estimate, and a
// constant rate is integrated exactly whatever the step: 30 deg/s for 2 s is 60 deg.
TEST(AttitudeFilter, ConstantRateWithTheAccelerometerOffIntegratesExactly) {
  const double rate = 30 * kDeg;
  struct Case {
    std::array<double, 3> gyro;
    double roll, pitch;
  };
  // Nose up is a negative rate about body y (left).
  for (const Case& c : {Case{{rate, 0, 0}, 60, 0}, Case{{-rate, 0, 0}, -60, 0},
                        Case{{0, -rate, 0}, 0, 60}, Case{{0, rate, 0}, 0, -60}}) {
    AttitudeFilter f;
    ASSERT_EQ(f.Init(OneSampleInit()), AttitudeError::kOk);
    ASSERT_EQ(f.Update(Sample(0, {0, 0, kG}, c.gyro)), AttitudeError::kOk);
    // Uneven steps (4..13 ms) ending exactly at 2 s: dt comes from the timestamps.
    std::int64_t t = 0;
    for (int i = 0; t < 2'000'000'000; ++i) {
      t = std::min<std::int64_t>(t + 4'000'000 + (i * 7'919'000) % 9'000'000, 2'000'000'000);
      ASSERT_EQ(f.Update(Sample(t, {0, 0, 0}, c.gyro)), AttitudeError::kOk);
      ASSERT_EQ(f.last_weight(), 0.0);
    }
    // The gyro sample is a float: 30 deg/s rounds by 3e-8 relative (2e-6 deg over 60).
    const double scale = static_cast<double>(static_cast<float>(rate)) / rate;
    EXPECT_NEAR(f.attitude().roll_deg, c.roll * scale, 1e-6);
    EXPECT_NEAR(f.attitude().pitch_deg, c.pitch * scale, 1e-6);
  }
}

// Level and converged, then a forward acceleration a for T = 1 s (f = (a, 0, g), no
// rotation). The correction's weight is k = max(0, 1 - (|f| - g) / gate) and the false
// vertical is beta = atan(a / g) away, so |e| <= sin(beta) and the estimate turns at most
// kp k sin(beta) rad/s from the proportional term plus the bias the integral has learnt
// meanwhile, at most ki k sin(beta) t: tip <= (kp T + ki T^2 / 2) k sin(beta).
TEST(AttitudeFilter, TransientAccelerationTipsLessThanTheGatedBound) {
  auto tip_deg = [](const AttitudeFilterParams& p, double a) {
    AttitudeFilter f;
    EXPECT_EQ(f.Init(p), AttitudeError::kOk);
    std::int64_t t = 0;
    EXPECT_EQ(f.Update(Sample(t, {0, 0, kG})), AttitudeError::kOk);
    Feed(f, &t, 200 * 10, {0, 0, kG});
    Feed(f, &t, 200, {a, 0, kG});
    return AngleBetween(f.up(), {0, 0, 1}) / kDeg;
  };
  auto bound_deg = [](const AttitudeFilterParams& p, double a) {
    const double k = std::max(0.0, 1 - (std::hypot(a, kG) - kG) / p.accel_gate_mps2);
    const double T = 1.0;
    return (p.kp * T + p.ki * T * T / 2) * k * std::sin(std::atan(a / kG)) / kDeg;
  };
  const AttitudeFilterParams defaults;
  // 3 m/s^2 moves |f| by 0.449 m/s^2, beyond the default gate (0.4): no tip at all.
  EXPECT_EQ(bound_deg(defaults, 3.0), 0.0);
  EXPECT_LT(tip_deg(defaults, 3.0), 1e-9);
  // A wider gate lets part of it through: the bound holds and is nearly reached (the
  // estimate moves towards the false vertical, so it slows a little).
  AttitudeFilterParams wide;
  wide.kp = 0.5;
  wide.ki = 0.02;
  wide.accel_gate_mps2 = 1.0;
  const double bound = bound_deg(wide, 3.0);  // 4.7 deg
  EXPECT_NEAR(bound, 4.71, 0.01);
  EXPECT_LE(tip_deg(wide, 3.0), bound);
  EXPECT_GE(tip_deg(wide, 3.0), 0.8 * bound);
  // Without a gate it heads for beta (17 deg): beta (1 - e^-kpT) in the small-angle limit.
  AttitudeFilterParams open = wide;
  open.accel_gate_mps2 = 1e9;
  EXPECT_GT(tip_deg(open, 3.0), 0.35 * std::atan(3.0 / kG) / kDeg);
  // Every acceleration up to 5 m/s^2 stays within its bound, whose largest value
  // (a = 1.61 m/s^2) is 6.48 deg for the defaults (kp = 1, ki = 0.08).
  double worst_bound = 0;
  for (double a = 0.25; a <= 5.0; a += 0.25) {
    EXPECT_LE(tip_deg(defaults, a), bound_deg(defaults, a) + 1e-9) << a;
    worst_bound = std::max(worst_bound, bound_deg(defaults, a));
  }
  EXPECT_LT(worst_bound, 6.49);
}

// A constant gyro bias b across the vertical, level and still. With ki = 0 the estimate
// settles where kp e cancels it: sin(alpha) = |b| / kp exactly. With ki the bias is learnt
// and the error goes to 0.
TEST(AttitudeFilter, IntegralGainRemovesAConstantGyroBias) {
  const std::array<double, 3> bias{0.5 * kDeg, -0.3 * kDeg, 0};
  AttitudeFilterParams p = OneSampleInit();
  p.ki = 0;
  AttitudeFilter f;
  ASSERT_EQ(f.Init(p), AttitudeError::kOk);
  std::int64_t t = 0;
  ASSERT_EQ(f.Update(Sample(t, {0, 0, kG}, bias)), AttitudeError::kOk);
  Feed(f, &t, 200 * 100, {0, 0, kG}, bias);
  const double want = std::asin(std::hypot(bias[0], bias[1]) / p.kp);  // 1.17 deg
  EXPECT_NEAR(AngleBetween(f.up(), {0, 0, 1}), want, 1e-6 * kDeg);
  // It settles at up = (-b_y, b_x, .) / kp.
  EXPECT_NEAR(f.up()[0], -bias[1] / p.kp, 1e-7);
  EXPECT_NEAR(f.up()[1], bias[0] / p.kp, 1e-7);

  AttitudeFilter d;
  ASSERT_EQ(d.Init(AttitudeFilterParams{}), AttitudeError::kOk);
  t = 0;
  ASSERT_EQ(d.Update(Sample(t, {0, 0, kG}, bias)), AttitudeError::kOk);
  Feed(d, &t, 200 * 600, {0, 0, kG}, bias);
  EXPECT_LT(AngleBetween(d.up(), {0, 0, 1}), 1e-6 * kDeg);
  EXPECT_NEAR(d.gyro_bias_radps()[0], static_cast<float>(bias[0]), 1e-9);
  EXPECT_NEAR(d.gyro_bias_radps()[1], static_cast<float>(bias[1]), 1e-9);
}

TEST(AttitudeFilter, TimestampErrorsAreValuesAndLeaveTheEstimate) {
  AttitudeFilter f;
  ASSERT_EQ(f.Init(OneSampleInit()), AttitudeError::kOk);
  // Free fall (or a dead sensor) cannot start the estimate.
  EXPECT_EQ(f.Update(Sample(0, {0, 0, 0})), AttitudeError::kNoGravity);
  EXPECT_FALSE(f.has_estimate());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(f.Update(Sample(0, {nan, 0, kG})), AttitudeError::kNonFinite);
  EXPECT_FALSE(f.has_estimate());
  const std::array<double, 3> tilted = Scaled(UpFromRollPitch(10, 0), kG);
  ASSERT_EQ(f.Update(Sample(1'000'000'000, tilted)), AttitudeError::kOk);
  const Attitude before = f.attitude();
  // The same time again, and an earlier one: ignored, whatever they say.
  EXPECT_EQ(f.Update(Sample(1'000'000'000, {0, 0, kG}, {1, 1, 1})),
            AttitudeError::kTimestampNotIncreasing);
  EXPECT_EQ(f.Update(Sample(999'000'000, {0, 0, kG}, {1, 1, 1})),
            AttitudeError::kTimestampNotIncreasing);
  EXPECT_EQ(f.Update(Sample(1'001'000'000, {0, kG, nan})), AttitudeError::kNonFinite);
  EXPECT_EQ(f.attitude().roll_deg, before.roll_deg);
  EXPECT_EQ(f.attitude().timestamp_ns, before.timestamp_ns);
  // Within max_gap_s (0.1 s): integrated.
  EXPECT_EQ(f.Update(Sample(1'100'000'000, tilted)), AttitudeError::kOk);
  // A gap: the estimate restarts from that sample's accelerometer, not the gyro.
  EXPECT_EQ(f.Update(Sample(1'300'000'000, Scaled(UpFromRollPitch(0, -20), kG), {5, 5, 5})),
            AttitudeError::kGap);
  EXPECT_NEAR(f.attitude().roll_deg, 0, 1e-5);
  EXPECT_NEAR(f.attitude().pitch_deg, -20, 1e-5);
  EXPECT_EQ(f.attitude().timestamp_ns, 1'300'000'000);
  f.Reset();
  EXPECT_FALSE(f.has_estimate());
  EXPECT_EQ(f.attitude().up[2], 1.0);
}

TEST(AttitudeFilter, UpdateDoesNotAllocate) {
  AttitudeFilter f;
  ASSERT_EQ(f.Init(AttitudeFilterParams{}), AttitudeError::kOk);
  ASSERT_TRUE(AllocationCounterActive());
  AllocationScope scope;
  std::int64_t t = 0;
  for (int i = 0; i < 2000; ++i) {
    t += kStepNs;
    const double s = std::sin(i * 0.01);
    ASSERT_EQ(f.Update(Sample(t, {s, 0.2, kG}, {0.1 * s, -0.2, 0.05})), AttitudeError::kOk);
    (void)f.attitude();
  }
  EXPECT_EQ(scope.allocations(), 0u);
}

}  // namespace
}  // namespace skyloc::dsp
