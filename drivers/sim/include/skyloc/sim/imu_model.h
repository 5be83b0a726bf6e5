// The simulated IMU: what an accelerometer and a gyroscope at the camera would read while
// the robot follows a trajectory (motion.h), with the errors of a MEMS IMU. And the
// attitude the dsp filter makes of it at each frame (EstimateAttitudes), for the
// gravity-aligned descriptor's experiments. docs/SIMULATOR.md, "IMU model".
//
// Motion between frames. The trajectory has poses only at frame times. The IMU needs an
// acceleration, so each coordinate (x, y, z, roll, pitch and the unwrapped yaw) is a
// cubic Hermite spline through the frame values with Catmull-Rom tangents
// (p[i+1] - p[i-1]) / (t[i+1] - t[i-1]) (one-sided at the ends; 0 across a stop where
// consecutive poses are equal, so a standing robot reads exactly still). It passes
// through every frame's pose exactly (the trajectories stay bit for bit what they are),
// has a continuous velocity and angular rate, and a piecewise-linear acceleration.
// Piecewise-linear angles (or slerp) would make the gyro a staircase with a jump at every
// frame: with +-15 deg bumps at 10 fps, steps of up to 3 deg a frame, 30 deg/s changes in
// 1/200 s (6000 deg/s^2). Catmull-Rom spreads that over the frame interval (~300 deg/s^2).
//
// The readings, body frame (x forward, y left, z up; R = Rz(yaw) Ry(-pitch) Rx(roll), as
// the renderer): specific force f = R^T (a_world + g z) and angular rate
// w = roll' x + pitch' (0, -cos roll, sin roll) + yaw' up, up = R^T z (the Euler-angle
// rates mapped to body rates; exact for this convention). The IMU sits at the camera: no
// lever arm. Bumps change roll and pitch only, not the height: no vertical bounce.
//
// Errors, per axis and sample (k = sample, dt = 1/rate, n ~ N(0, 1) from the seeded
// SplitMix64 stream of random.h):
//   reading = truth + bias + bias_walk[k] + density * sqrt(rate) * n
//   bias_walk[k+1] = bias_walk[k] + walk * sqrt(dt) * n
// (the continuous-time white-noise density of the datasheets sampled at `rate`, the
// convention of IEEE Std 952 and Kalibr.)
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "skyloc/dsp/attitude_filter.h"
#include "skyloc/dsp/imu.h"
#include "skyloc/platform/status.h"
#include "skyloc/sim/motion.h"

namespace skyloc::sim {

// Defaults: a BMI160 (Bosch Sensortec BST-BMI160-DS000-07, rev. 0.8, 2015, table 1):
// accelerometer output noise 180 ug/sqrt(Hz), zero-g offset +-40 mg; gyroscope output
// noise 0.007 deg/s/sqrt(Hz), zero-rate offset +-3 deg/s. (An MPU-6050, InvenSense
// PS-MPU-6000A-00 rev. 3.4: 400 ug/sqrt(Hz), 0.005 deg/s/sqrt(Hz), +-20 deg/s initial ZRO.)
// Offsets: the datasheet figures are before calibration. A product calibrates the
// accelerometer once (six positions: a few mg remain; 40 mg would tilt roll/pitch by
// 2.3 deg and no filter can remove it) and takes the gyro's mean while standing at start
// (a residual of a fraction of a deg/s); those residuals are the defaults, different per
// axis. The datasheets give no in-run bias instability; the walks are typical consumer
// MEMS values (0.13 deg/s and 2 mg of drift over 500 s).
struct ImuModelConfig {
  double rate_hz = 200;  // sample rate (BMI160 ODR 25..1600 Hz; 200 Hz: 20 per 10 fps frame)
  double accel_noise_density = 180e-6 * dsp::kStandardGravity;     // m/s^2 / sqrt(Hz)
  double gyro_noise_density = 0.007 * 0.017453292519943295;        // rad/s / sqrt(Hz)
  std::array<double, 3> accel_bias_mps2{0.03, -0.04, 0.05};        // ~3..5 mg
  std::array<double, 3> gyro_bias_radps{0.0087, -0.0070, 0.0052};  // 0.5, -0.4, 0.3 deg/s
  double accel_bias_walk = 1e-3;                                   // m/s^2 / sqrt(s)
  double gyro_bias_walk = 1e-4;                                    // rad/s / sqrt(s)
  double gravity_mps2 = dsp::kStandardGravity;
  std::uint64_t seed = 1;
};

// The same rate with every error off: the readings are the motion's truth.
ImuModelConfig IdealImu(double rate_hz = 200);

// IMU samples at rate_hz from the first frame's time to the last's (inclusive when it
// falls on a sample), timestamps in ns from the trajectory's clock (time_s). Needs at
// least 2 frames with increasing times. Allocates `out` (start-up work). Deterministic for
// a seed, the same on every build.
Status SimulateImu(std::span<const TrajectoryPoint> trajectory, const ImuModelConfig& config,
                   std::vector<dsp::ImuSample>* out);

// The true motion at time t (s) as the IMU model sees it: the interpolated pose (angles in
// degrees), the specific force and the body rate without sensor errors. For tests.
struct ImuTruth {
  drivers::Pose pose;
  std::array<double, 3> specific_force_mps2{};
  std::array<double, 3> gyro_radps{};
};
Status ImuTruthAt(std::span<const TrajectoryPoint> trajectory, double t, double gravity_mps2,
                  ImuTruth* out);

// The IMU noise and bias seed of a simulated run, from the run's own seed (its stops,
// bumps and clouds): one rule for the experiments and the firmware's [attitude] kind = "sim".
inline std::uint64_t ImuSeedForRun(std::uint64_t run_seed) {
  return run_seed * 7919 + 17;
}

// Runs the simulated IMU through dsp::AttitudeFilter and returns, for each frame, the
// filter's latest estimate at or before the frame's timestamp (frame and attitude matched
// by timestamp; the estimate's own timestamp is the IMU sample's). `at_frames` gets one
// entry per trajectory point.
Status EstimateAttitudes(std::span<const TrajectoryPoint> trajectory, const ImuModelConfig& imu,
                         const dsp::AttitudeFilterParams& filter,
                         std::vector<dsp::Attitude>* at_frames);

// Roll and pitch error of estimates against the trajectory's true poses (degrees).
struct AttitudeErrorStats {
  double roll_rms_deg = 0, pitch_rms_deg = 0;
  double roll_max_deg = 0, pitch_max_deg = 0;
  double tilt_rms_deg = 0, tilt_max_deg = 0;  // angle between the true and estimated up
};
AttitudeErrorStats CompareAttitudes(std::span<const TrajectoryPoint> trajectory,
                                    std::span<const dsp::Attitude> estimates);

}  // namespace skyloc::sim
