#include "skyloc/dsp/attitude_filter.h"

#include <algorithm>
#include <cmath>

namespace skyloc::dsp {

namespace {

using Vec = std::array<double, 3>;

Vec Cross(const Vec& a, const Vec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double Dot(const Vec& a, const Vec& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
double Norm(const Vec& a) {
  return std::sqrt(Dot(a, a));
}

// exp([r]x) v: v rotated by the rotation vector r (angle |r| about r/|r|), Rodrigues.
Vec Rotate(const Vec& r, const Vec& v) {
  const double t2 = Dot(r, r);
  double c, s, k;   // cos(t), sin(t)/t, (1 - cos(t))/t^2
  if (t2 < 1e-8) {  // series to t^4: below 1e-16 relative error
    c = 1 - t2 / 2 + t2 * t2 / 24;
    s = 1 - t2 / 6 + t2 * t2 / 120;
    k = 0.5 - t2 / 24 + t2 * t2 / 720;
  } else {
    const double t = std::sqrt(t2);
    c = std::cos(t);
    s = std::sin(t) / t;
    k = (1 - c) / t2;
  }
  const Vec rxv = Cross(r, v);
  const double rv = Dot(r, v);
  return {v[0] * c + rxv[0] * s + r[0] * rv * k, v[1] * c + rxv[1] * s + r[1] * rv * k,
          v[2] * c + rxv[2] * s + r[2] * rv * k};
}

Vec ToVec(const std::array<float, 3>& a) {
  return {static_cast<double>(a[0]), static_cast<double>(a[1]), static_cast<double>(a[2])};
}

bool Finite(const ImuSample& s) {
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(s.accel_mps2[static_cast<std::size_t>(i)]) ||
        !std::isfinite(s.gyro_radps[static_cast<std::size_t>(i)]))
      return false;
  }
  return true;
}

}  // namespace

const char* AttitudeErrorMessage(AttitudeError error) {
  switch (error) {
    case AttitudeError::kOk:
      return "ok";
    case AttitudeError::kBadGain:
      return "attitude filter gain kp must be 0..100 1/s (1/kp is the time constant)";
    case AttitudeError::kBadIntegralGain:
      return "attitude filter integral gain ki must be 0..100 1/s^2";
    case AttitudeError::kBadGate:
      return "attitude filter accelerometer gate must be a positive m/s^2";
    case AttitudeError::kBadGravity:
      return "attitude filter gravity must be 9.7..9.9 m/s^2";
    case AttitudeError::kBadMaxGap:
      return "attitude filter max gap must be more than 0 and at most 10 s";
    case AttitudeError::kBadInitSamples:
      return "attitude filter init_samples must be 1..10000";
    case AttitudeError::kBadMaxBias:
      return "attitude filter max gyro bias must be >= 0 rad/s";
    case AttitudeError::kNotInitialised:
      return "attitude filter used before Init succeeded";
    case AttitudeError::kNonFinite:
      return "IMU sample with a NaN or infinite value (ignored)";
    case AttitudeError::kTimestampNotIncreasing:
      return "IMU sample timestamp at or before the previous sample's (ignored)";
    case AttitudeError::kGap:
      return "gap in the IMU samples longer than max_gap_s: attitude restarted from the "
             "accelerometer";
    case AttitudeError::kNoGravity:
      return "accelerometer reads ~0 m/s^2 while initialising (free fall or a dead sensor; "
             "sample ignored)";
  }
  return "unknown attitude filter error";
}

AttitudeError ValidateAttitudeFilterParams(const AttitudeFilterParams& p) {
  if (!(p.kp >= 0 && p.kp <= 100))
    return AttitudeError::kBadGain;
  if (!(p.ki >= 0 && p.ki <= 100))
    return AttitudeError::kBadIntegralGain;
  if (!(p.accel_gate_mps2 > 0 && std::isfinite(p.accel_gate_mps2)))
    return AttitudeError::kBadGate;
  if (!(p.gravity_mps2 >= 9.7 && p.gravity_mps2 <= 9.9))
    return AttitudeError::kBadGravity;
  if (!(p.max_gap_s > 0 && p.max_gap_s <= 10))
    return AttitudeError::kBadMaxGap;
  if (p.init_samples < 1 || p.init_samples > 10000)
    return AttitudeError::kBadInitSamples;
  if (!(p.max_bias_radps >= 0 && std::isfinite(p.max_bias_radps)))
    return AttitudeError::kBadMaxBias;
  return AttitudeError::kOk;
}

AttitudeError AttitudeFilter::Init(const AttitudeFilterParams& params) {
  initialised_ = false;
  if (const AttitudeError e = ValidateAttitudeFilterParams(params); e != AttitudeError::kOk)
    return e;
  params_ = params;
  initialised_ = true;
  Reset();
  return AttitudeError::kOk;
}

void AttitudeFilter::Reset() {
  have_sample_ = false;
  init_left_ = 0;
  last_ns_ = 0;
  up_ = {0, 0, 1};
  init_sum_ = {0, 0, 0};
  bias_ = {0, 0, 0};
  last_gyro_ = {0, 0, 0};
  last_weight_ = 0;
}

void AttitudeFilter::StartFrom(const ImuSample& sample) {
  const Vec a = ToVec(sample.accel_mps2);
  const double n = Norm(a);
  init_sum_ = a;
  up_ = {a[0] / n, a[1] / n, a[2] / n};
  init_left_ = params_.init_samples - 1;
  have_sample_ = true;
  last_ns_ = sample.timestamp_ns;
  last_gyro_ = ToVec(sample.gyro_radps);
  last_weight_ = 0;
}

AttitudeError AttitudeFilter::Update(const ImuSample& sample) {
  if (!initialised_)
    return AttitudeError::kNotInitialised;
  if (!Finite(sample))
    return AttitudeError::kNonFinite;
  const Vec a = ToVec(sample.accel_mps2);
  const double f = Norm(a);
  const bool no_gravity = !(f > 0.1 * params_.gravity_mps2);
  if (!have_sample_) {
    if (no_gravity)
      return AttitudeError::kNoGravity;
    StartFrom(sample);
    return AttitudeError::kOk;
  }
  if (sample.timestamp_ns <= last_ns_)
    return AttitudeError::kTimestampNotIncreasing;
  const double dt = static_cast<double>(sample.timestamp_ns - last_ns_) * 1e-9;
  if (dt > params_.max_gap_s) {
    if (no_gravity) {  // cannot restart from this one: wait for the next
      have_sample_ = false;
      return AttitudeError::kNoGravity;
    }
    StartFrom(sample);
    return AttitudeError::kGap;
  }
  if (init_left_ > 0 && no_gravity)
    return AttitudeError::kNoGravity;
  const Vec gyro = ToVec(sample.gyro_radps);
  // The rate over the step: trapezoid of the two samples, less the learned bias.
  Vec w{0.5 * (last_gyro_[0] + gyro[0]) - bias_[0], 0.5 * (last_gyro_[1] + gyro[1]) - bias_[1],
        0.5 * (last_gyro_[2] + gyro[2]) - bias_[2]};
  last_ns_ = sample.timestamp_ns;
  last_gyro_ = gyro;
  const Vec step{-w[0] * dt, -w[1] * dt, -w[2] * dt};

  if (init_left_ > 0) {  // averaging the first accelerometer samples, carried by the gyro
    const Vec s = Rotate(step, init_sum_);
    init_sum_ = {s[0] + a[0], s[1] + a[1], s[2] + a[2]};
    const double n = Norm(init_sum_);
    up_ = {init_sum_[0] / n, init_sum_[1] / n, init_sum_[2] / n};
    --init_left_;
    last_weight_ = 0;
    return AttitudeError::kOk;
  }

  const double weight =
      no_gravity
          ? 0.0
          : std::max(0.0, 1.0 - std::abs(f - params_.gravity_mps2) / params_.accel_gate_mps2);
  last_weight_ = weight;
  Vec e{0, 0, 0};
  if (weight > 0) {
    const Vec am{a[0] / f, a[1] / f, a[2] / f};
    e = Cross(am, up_);
  }
  for (std::size_t i = 0; i < 3; ++i)
    w[i] += params_.kp * weight * e[i];
  up_ = Rotate({-w[0] * dt, -w[1] * dt, -w[2] * dt}, up_);
  const double n = Norm(up_);
  up_ = {up_[0] / n, up_[1] / n, up_[2] / n};
  if (params_.ki > 0 && weight > 0) {
    for (std::size_t i = 0; i < 3; ++i) {
      bias_[i] = std::clamp(bias_[i] - params_.ki * weight * e[i] * dt, -params_.max_bias_radps,
                            params_.max_bias_radps);
    }
  }
  return AttitudeError::kOk;
}

Attitude AttitudeFilter::attitude() const {
  if (!have_sample_)
    return Attitude{};
  return AttitudeFromUp(last_ns_, up_);
}

}  // namespace skyloc::dsp
