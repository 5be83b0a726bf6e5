#include "skyloc/drivers/imu_device.h"

#include <cmath>
#include <cstring>

#include "skyloc/dsp/angles.h"

namespace skyloc::drivers {
namespace {

// sin and cos of an angle in degrees, exact for multiples of 90 degrees (so an axis remap
// gives a matrix of exact 0 and +-1).
void SinCosDeg(double deg, double* s, double* c) {
  const double quarter = deg / 90.0;
  if (quarter == std::round(quarter) && std::fabs(quarter) < 1e9) {
    const auto q = static_cast<long long>(std::round(quarter));
    const int k = static_cast<int>(((q % 4) + 4) % 4);
    constexpr double kSin[4] = {0, 1, 0, -1};
    constexpr double kCos[4] = {1, 0, -1, 0};
    *s = kSin[k];
    *c = kCos[k];
    return;
  }
  *s = std::sin(deg * dsp::kDegToRad);
  *c = std::cos(deg * dsp::kDegToRad);
}

bool Finite(const ImuMounting& m) {
  return std::isfinite(m.roll_deg) && std::isfinite(m.pitch_deg) && std::isfinite(m.yaw_deg);
}

}  // namespace

Result<std::array<double, 9>> ImuMountingMatrix(const ImuMounting& m) {
  if (!Finite(m)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "IMU mounting roll/pitch/yaw must be finite degrees (got %g, %g, %g)",
                         m.roll_deg, m.pitch_deg, m.yaw_deg);
  }
  double sr = 0, cr = 0, sp = 0, cp = 0, sy = 0, cy = 0;
  SinCosDeg(m.roll_deg, &sr, &cr);
  SinCosDeg(m.pitch_deg, &sp, &cp);
  SinCosDeg(m.yaw_deg, &sy, &cy);
  // Rz(yaw) * Ry(pitch) * Rx(roll).
  return std::array<double, 9>{cy * cp,
                               cy * sp * sr - sy * cr,
                               cy * sp * cr + sy * sr,
                               sy * cp,
                               sy * sp * sr + cy * cr,
                               sy * sp * cr - cy * sr,
                               -sp,
                               cp * sr,
                               cp * cr};
}

Result<ImuMounting> ImuMountingFromAxes(const char* axes) {
  const char* text = axes != nullptr ? axes : "";
  std::array<double, 9> r{};
  std::array<bool, 3> used{};
  const char* p = text;
  for (int row = 0; row < 3; ++row) {
    while (*p == ' ')
      ++p;
    double sign = 1.0;
    if (*p == '+' || *p == '-') {
      sign = *p == '-' ? -1.0 : 1.0;
      ++p;
    }
    const char axis = *p;
    const int column = axis == 'x' || axis == 'X'   ? 0
                       : axis == 'y' || axis == 'Y' ? 1
                       : axis == 'z' || axis == 'Z' ? 2
                                                    : -1;
    if (column < 0 || used[static_cast<std::size_t>(column)]) {
      return Status::Error(StatusCode::kInvalidArgument,
                           "IMU axes '%s': expected three signed axes, each of x, y, z once "
                           "(e.g. \"x,-y,-z\" for a board mounted upside down)",
                           text);
    }
    used[static_cast<std::size_t>(column)] = true;
    r[static_cast<std::size_t>(row * 3 + column)] = sign;
    ++p;
    while (*p == ' ')
      ++p;
    if (row < 2) {
      if (*p != ',') {
        return Status::Error(StatusCode::kInvalidArgument,
                             "IMU axes '%s': expected three comma-separated signed axes "
                             "(e.g. \"x,-y,-z\")",
                             text);
      }
      ++p;
    }
  }
  if (*p != '\0') {
    return Status::Error(StatusCode::kInvalidArgument,
                         "IMU axes '%s': unexpected text after the third axis", text);
  }
  const double det = r[0] * (r[4] * r[8] - r[5] * r[7]) - r[1] * (r[3] * r[8] - r[5] * r[6]) +
                     r[2] * (r[3] * r[7] - r[4] * r[6]);
  if (det < 0) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "IMU axes '%s' is a mirror image, not a rotation: flip the sign of one "
                         "axis (a right-handed IMU stays right-handed whichever way it is "
                         "mounted)",
                         text);
  }
  // R = Rz(yaw) Ry(pitch) Rx(roll): R[6] = -sin(pitch), R[7] = cos(pitch) sin(roll),
  // R[8] = cos(pitch) cos(roll), R[3] = sin(yaw) cos(pitch), R[0] = cos(yaw) cos(pitch).
  ImuMounting m;
  if (r[6] == 1.0 || r[6] == -1.0) {
    // Pitch +-90 degrees (gimbal lock): roll 0, the yaw carries the rest.
    m.pitch_deg = r[6] < 0 ? 90.0 : -90.0;
    m.roll_deg = 0.0;
    m.yaw_deg = std::atan2(-r[1], r[4]) * dsp::kRadToDeg;
  } else {
    m.pitch_deg = std::asin(-r[6]) * dsp::kRadToDeg;
    m.roll_deg = std::atan2(r[7], r[8]) * dsp::kRadToDeg;
    m.yaw_deg = std::atan2(r[3], r[0]) * dsp::kRadToDeg;
  }
  return m;
}

const char* ImuStateName(ImuDevice::State state) {
  switch (state) {
    case ImuDevice::State::kClosed:
      return "closed";
    case ImuDevice::State::kOpen:
      return "open";
    case ImuDevice::State::kStreaming:
      return "streaming";
  }
  return "unknown";
}

Status ImuDevice::SetMounting(const ImuMounting& mounting) {
  if (state_ != State::kClosed) {
    return Status::Error(StatusCode::kFailedPrecondition,
                         "imu %s: SetMounting() while %s (set it before Open())", info_.name,
                         ImuStateName(state_));
  }
  if (!Finite(mounting)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "imu %s: mounting roll/pitch/yaw must be finite degrees", info_.name);
  }
  mounting_ = mounting;
  return Status::Ok();
}

Status ImuDevice::Open() {
  if (state_ != State::kClosed) {
    return Status::Error(StatusCode::kFailedPrecondition, "imu %s: Open() while %s", info_.name,
                         ImuStateName(state_));
  }
  Result<std::array<double, 9>> rotation = ImuMountingMatrix(mounting_);
  if (!rotation.ok()) {
    Status s = rotation.status();
    return s.AddContext("imu %s", info_.name);
  }
  rotation_ = *rotation;
  SKYLOC_TRY(DoOpen());
  recovery_ = StreamRecovery(recovery_config_);
  state_ = State::kOpen;
  return Status::Ok();
}

Status ImuDevice::Start() {
  if (state_ != State::kOpen) {
    return Status::Error(StatusCode::kFailedPrecondition, "imu %s: Start() while %s", info_.name,
                         ImuStateName(state_));
  }
  // Stopped during an outage, the device is closed: Read() goes on reopening it.
  if (recovery_.state() == StreamRecovery::State::kStreaming) {
    SKYLOC_TRY(DoStart());
    recovery_.Started(clock_->Now());
  }
  state_ = State::kStreaming;
  return Status::Ok();
}

void ImuDevice::Lost() {
  DoStop();
  DoClose();
  recovery_.DeviceLost(clock_->Now());
  last_reopen_error_ = Status::Ok();
  ++counters_.outages;
}

Status ImuDevice::Reopen() {
  const Nanoseconds now = clock_->Now();
  if (recovery_.state() == StreamRecovery::State::kFailed) {
    return Status::Error(StatusCode::kUnavailable,
                         "imu %s: gone; gave up after %u failed reopens (last: %s): check its "
                         "wiring, then restart skyloc",
                         info_.name, recovery_.consecutive_failures(),
                         last_reopen_error_.message());
  }
  if (!recovery_.ReopenDue(now)) {
    return Status::Error(
        StatusCode::kUnavailable, "imu %s: gone; next reopen attempt in %lld ms (last attempt: %s)",
        info_.name, static_cast<long long>((recovery_.next_attempt() - now).count() / 1'000'000),
        recovery_.consecutive_failures() == 0 ? "none yet" : last_reopen_error_.message());
  }
  Status s = DoOpen();
  if (s.ok())
    s = DoStart();
  if (!s.ok()) {
    DoClose();
    recovery_.ReopenFailed(now);
    last_reopen_error_ = s;
    return Status::Error(StatusCode::kUnavailable, "imu %s: gone; reopen %u failed: %s", info_.name,
                         recovery_.consecutive_failures(), s.message());
  }
  recovery_.ReopenSucceeded(now);
  ++counters_.reopens;
  return Status::Ok();
}

Result<std::size_t> ImuDevice::Read(std::span<dsp::ImuSample> out, Nanoseconds timeout) {
  if (state_ != State::kStreaming) {
    ++counters_.errors;
    return Status::Error(StatusCode::kFailedPrecondition, "imu %s: Read() while %s", info_.name,
                         ImuStateName(state_));
  }
  if (out.empty()) {
    ++counters_.errors;
    return Status::Error(StatusCode::kInvalidArgument,
                         "imu %s: Read() into an empty span (give room for one sample at least)",
                         info_.name);
  }
  if (recovery_.state() != StreamRecovery::State::kStreaming) {
    if (Status reopened = Reopen(); !reopened.ok()) {
      ++counters_.errors;
      return reopened;
    }
  }
  Result<std::size_t> n = DoRead(out, timeout < Nanoseconds(0) ? Nanoseconds(0) : timeout);
  if (!n.ok()) {
    const StatusCode code = n.status().code();
    if (code != StatusCode::kDeadlineExceeded && code != StatusCode::kOutOfRange)
      ++counters_.errors;
    if (code == StatusCode::kUnavailable)
      Lost();
    return n;
  }
  if (*n == 0 || *n > out.size()) {
    ++counters_.errors;
    return Status::Error(StatusCode::kInternal, "imu %s: the driver returned %zu samples for %zu",
                         info_.name, *n, out.size());
  }
  const std::array<double, 9>& r = rotation_;
  for (std::size_t i = 0; i < *n; ++i) {
    dsp::ImuSample& s = out[i];
    for (std::array<float, 3>* v : {&s.accel_mps2, &s.gyro_radps}) {
      const double x = (*v)[0], y = (*v)[1], z = (*v)[2];
      (*v)[0] = static_cast<float>(r[0] * x + r[1] * y + r[2] * z);
      (*v)[1] = static_cast<float>(r[3] * x + r[4] * y + r[5] * z);
      (*v)[2] = static_cast<float>(r[6] * x + r[7] * y + r[8] * z);
    }
  }
  counters_.samples += *n;
  return n;
}

void ImuDevice::Stop() {
  if (state_ != State::kStreaming)
    return;
  if (recovery_.state() == StreamRecovery::State::kStreaming)
    DoStop();  // else the outage closed it
  state_ = State::kOpen;
}

void ImuDevice::Close() {
  Stop();
  if (state_ != State::kOpen)
    return;
  DoClose();
  state_ = State::kClosed;
}

}  // namespace skyloc::drivers
