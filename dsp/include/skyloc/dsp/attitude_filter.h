// The attitude filter: roll and pitch (the gravity direction in the body frame) from a
// stream of IMU samples, by a Mahony complementary filter (Mahony, Hamel, Pflimlin 2008,
// "Nonlinear complementary filters on the special orthogonal group", IEEE TAC 53(5)).
// docs/ATTITUDE.md has the equations, the gains and what the tests prove.
//
// State: the unit zenith `up` in the body frame and a gyro bias estimate b, not a full
// quaternion. Gravity observes two of the three rotational degrees of freedom; yaw is not
// observable, not needed (the sky descriptor is yaw invariant) and would only drift.
// Keeping exactly the observable part means no yaw to renormalise or to leak into roll
// and pitch through a numerically drifting quaternion, and `up` is what the gravity-
// aligned descriptor consumes. The body sees a world-fixed vector turn the other way:
//     d(up)/dt = -w x up = up x w
// Per sample (dt from the timestamps):
//     a  = f / |f|                                measured zenith (specific force)
//     k  = gate weight in [0, 1] from | |f| - g |  (below)
//     e  = a x up                                 correction axis, |e| = sin(angle(up, a))
//     w  = (gyro_prev + gyro) / 2 - b + kp k e     rate over the step (trapezoid)
//     up <- exp(-[w dt]x) up                      exact rotation (Rodrigues), renormalised
//     b  <- b - ki k e dt                         integral action: gyro bias
// A constant rate with the correction gated off is integrated exactly (the rotation
// exponential, not an Euler step). With a constant tilt and ki = 0 the angle alpha between
// up and a obeys d(alpha)/dt = -kp sin(alpha), i.e. tan(alpha/2) = tan(alpha0/2) e^{-kp t}.
// With a constant gyro bias b and ki = 0 the estimate settles sin(alpha) = |b_perp| / kp
// off the truth (b_perp: the bias across up); ki > 0 drives that to 0.
//
// Accelerometer gating: the accelerometer measures gravity only when the body does not
// accelerate. |f| = sqrt(g^2 + 2 g a_z + |a|^2), so any acceleration that changes |f| by
// more than accel_gate_mps2 switches the correction off; below, the weight falls linearly:
//     k = max(0, 1 - | |f| - g | / accel_gate_mps2)
// A horizontal acceleration a moves |f| by about a^2 / (2 g): 3 m/s^2 gives 0.45 m/s^2,
// gated off by the default 0.4 (which gates everything above 2.83 m/s^2). The largest
// leak is at a = sqrt(2 g gate / 3) (1.61 m/s^2 for the default), where k sin(beta) = 0.109
// (beta = atan(a / g), the false vertical's tilt): the estimate then moves towards the
// false vertical at most kp k sin(beta) rad/s (6.2 deg/s for kp = 1, and only while such
// an acceleration lasts). A gate on |f| cannot see small horizontal accelerations; the
// time constant 1/kp is what bounds their effect.
//
// Fixed memory, no allocation, no exceptions, no OS header (dsp rule).
#pragma once

#include <array>
#include <cstdint>

#include "skyloc/dsp/imu.h"

namespace skyloc::dsp {

enum class AttitudeError : std::uint8_t {
  kOk = 0,
  kBadGain,                 // kp not finite or outside 0..100 1/s
  kBadIntegralGain,         // ki not finite or outside 0..100 1/s^2
  kBadGate,                 // accel_gate_mps2 not finite or <= 0
  kBadGravity,              // gravity_mps2 outside 9.7..9.9
  kBadMaxGap,               // max_gap_s not finite or outside 0..10 s (exclusive of 0)
  kBadInitSamples,          // init_samples outside 1..10000
  kBadMaxBias,              // max_bias_radps not finite or < 0
  kNotInitialised,          // Update before a successful Init
  kNonFinite,               // a sample with a NaN or infinite value (ignored)
  kTimestampNotIncreasing,  // timestamp at or before the previous sample's (ignored)
  kGap,        // more than max_gap_s since the previous sample: restarted from this one
  kNoGravity,  // the accelerometer reads (almost) 0 while initialising (ignored)
};

// A sentence saying what is wrong, for the caller to turn into its error.
const char* AttitudeErrorMessage(AttitudeError error);

struct AttitudeFilterParams {
  // Proportional gain, 1/s: the complementary filter's crossover frequency (rad/s), i.e.
  // time constant 1/kp = 1 s. Above 0.16 Hz the gyro alone makes the estimate, below it
  // the accelerometer. The gyro's white noise integrates to 0.007 deg/s/sqrt(Hz) x
  // sqrt(1 s) = 0.007 deg over that time: nothing. What limits kp from above is horizontal
  // acceleration the gate cannot see (an ungated 1 m/s^2 for 1 s tilts at most
  // kp x 1 s x atan(1/9.8) = 5.8 deg); from below, the gyro bias before ki has learned it
  // (error asin(|b| / kp): 0.64 deg for 0.64 deg/s) and a bias that cannot be learned
  // while the gate is shut. Measured on simulated runs (docs/ATTITUDE.md): kp = 0.5 halves
  // the error of a 10 m/s run with speed jitter, kp = 1 wins there by 2x and loses 20 % of
  // the worst case of a 1 m/s run.
  double kp = 1.0;
  // Integral gain, 1/s^2: learns the gyro bias. The loop s^2 + kp s + ki has roots near
  // -kp and -ki/kp for ki << kp^2/4 (overdamped: ki = kp^2 / 12.5, zeta = 1.8): 0.08
  // learns the bias with a 12.5 s time constant, slow enough that a passing acceleration
  // does not teach it a false bias.
  double ki = 0.08;
  // The correction weight falls linearly from 1 at |f| = g to 0 at | |f| - g | = gate.
  // 0.4 m/s^2 (0.04 g): 10x the |f| noise of a MEMS accelerometer at 200 Hz (BMI160:
  // 180 ug/sqrt(Hz) -> 0.025 m/s^2), above the spread of local gravity (9.78..9.83), and a
  // 3 m/s^2 horizontal acceleration is gated completely (docs above).
  double accel_gate_mps2 = 0.4;
  double gravity_mps2 = kStandardGravity;
  // A longer silence than this is a gap: the gyro cannot be integrated across it, so the
  // filter starts again from the accelerometer (keeping the learned bias).
  double max_gap_s = 0.1;
  // The first estimate is the mean direction of this many accelerometer samples (each
  // rotated along with the gyro), before the correction loop starts.
  int init_samples = 10;
  // The bias estimate is clamped to +-this on each axis (anti-windup): 10 deg/s.
  double max_bias_radps = 0.17453292519943295;
};

AttitudeError ValidateAttitudeFilterParams(const AttitudeFilterParams& params);

class AttitudeFilter {
 public:
  // Validates and keeps the parameters; forgets everything (Reset).
  AttitudeError Init(const AttitudeFilterParams& params);
  // Forgets the attitude, the bias and the last timestamp: the next sample starts again.
  void Reset();

  // One sample, in timestamp order. kTimestampNotIncreasing, kNonFinite and kNoGravity
  // leave the state untouched; kGap restarts the estimate from this sample (bias kept).
  AttitudeError Update(const ImuSample& sample);

  // True once the first sample has given an estimate.
  bool has_estimate() const { return have_sample_; }
  // True once init_samples samples were averaged and the correction loop runs.
  bool converging() const { return have_sample_ && init_left_ == 0; }
  // The current estimate (level with timestamp 0 before the first sample).
  Attitude attitude() const;
  const std::array<double, 3>& up() const { return up_; }
  const std::array<double, 3>& gyro_bias_radps() const { return bias_; }
  // The gate weight of the last sample's accelerometer reading (0: correction off).
  double last_weight() const { return last_weight_; }
  const AttitudeFilterParams& params() const { return params_; }

 private:
  void StartFrom(const ImuSample& sample);

  AttitudeFilterParams params_;
  bool initialised_ = false;
  bool have_sample_ = false;
  int init_left_ = 0;
  std::int64_t last_ns_ = 0;
  std::array<double, 3> up_{0, 0, 1};
  std::array<double, 3> init_sum_{0, 0, 0};  // accelerometer sum while initialising
  std::array<double, 3> bias_{0, 0, 0};
  std::array<double, 3> last_gyro_{0, 0, 0};
  double last_weight_ = 0;
};

}  // namespace skyloc::dsp
