// Inertial samples and the robot's attitude, shared by the attitude sources (drivers/), the
// attitude filter and the gravity-aligned sky descriptor (dsp/).
//
// The frame: the *body frame of the camera's lens model* (dsp::Lens: body = R_mount *
// camera, from camera.toml's mount angles), the frame the sky descriptor samples in; an
// attitude source's mounting rotation takes the IMU's axes into it. On a robot whose camera
// mount angles describe the camera on the robot, that is the robot's frame (x forward, y
// left, z up), as in the simulator (sim::DefaultSimLens carries its camera's mount).
// Angles (the simulator's convention, drivers/sim/src/renderer.cpp BodyToWorld):
//   body-to-world R = Rz(yaw) * Ry(-pitch) * Rx(roll), so a positive pitch lifts the nose
//   (+x) and a positive roll lowers the right (-y) side.
//   The world's zenith seen in the body frame is therefore
//     up = (sin pitch, cos pitch sin roll, cos pitch cos roll)
//   and an accelerometer at rest reads the specific force f = g * up (+9.81 m/s^2 on z when
//   level): roll = atan2(up_y, up_z), pitch = atan2(up_x, hypot(up_y, up_z)).
// Yaw is not observable from gravity and is not part of Attitude.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

#include "skyloc/dsp/angles.h"

namespace skyloc::dsp {

inline constexpr double kStandardGravity = 9.80665;  // m/s^2

// One IMU reading in the body frame (after the mounting rotation).
struct ImuSample {
  std::int64_t timestamp_ns = 0;      // CLOCK_MONOTONIC (or the dataset's / simulator's clock)
  std::array<float, 3> accel_mps2{};  // specific force: +g on z when level and still
  std::array<float, 3> gyro_radps{};  // angular rate about body x, y, z (right-handed)
};

// Roll and pitch of the body, and the zenith as a unit vector in the body frame.
struct Attitude {
  std::int64_t timestamp_ns = 0;
  double roll_deg = 0;
  double pitch_deg = 0;
  std::array<double, 3> up{0, 0, 1};
};

inline std::array<double, 3> UpFromRollPitch(double roll_deg, double pitch_deg) {
  const double r = roll_deg * kDegToRad, p = pitch_deg * kDegToRad;
  return {std::sin(p), std::cos(p) * std::sin(r), std::cos(p) * std::cos(r)};
}

inline Attitude AttitudeFromRollPitch(std::int64_t timestamp_ns, double roll_deg,
                                      double pitch_deg) {
  return {timestamp_ns, roll_deg, pitch_deg, UpFromRollPitch(roll_deg, pitch_deg)};
}

// `up` need not be unit length (e.g. an accelerometer reading); it must not be zero.
inline Attitude AttitudeFromUp(std::int64_t timestamp_ns, const std::array<double, 3>& up) {
  const double n = std::sqrt(up[0] * up[0] + up[1] * up[1] + up[2] * up[2]);
  const std::array<double, 3> u{up[0] / n, up[1] / n, up[2] / n};
  return {timestamp_ns, std::atan2(u[1], u[2]) * kRadToDeg,
          std::atan2(u[0], std::hypot(u[1], u[2])) * kRadToDeg, u};
}

}  // namespace skyloc::dsp
