#include "skyloc/sim/imu_model.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "skyloc/drivers/dsp_status.h"
#include "skyloc/dsp/angles.h"
#include "skyloc/sim/random.h"

namespace skyloc::sim {

namespace {

constexpr int kChannels = 6;  // x, y, z, roll, pitch, unwrapped yaw

using Vec = std::array<double, 3>;

// The trajectory as cubic Hermite splines with Catmull-Rom tangents (imu_model.h).
class Spline {
 public:
  Status Build(std::span<const TrajectoryPoint> trajectory) {
    const std::size_t n = trajectory.size();
    if (n < 2)
      return Status::Error(StatusCode::kInvalidArgument,
                           "IMU model: the trajectory needs at least 2 frames, it has %zu", n);
    times_.resize(n);
    values_.resize(n);
    tangents_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const TrajectoryPoint& p = trajectory[i];
      times_[i] = p.time_s;
      if (!std::isfinite(p.time_s) || (i > 0 && !(p.time_s > times_[i - 1])))
        return Status::Error(StatusCode::kInvalidArgument,
                             "IMU model: frame %zu's time %.9f s does not follow the previous "
                             "frame's (times must increase)",
                             i, p.time_s);
      double yaw = p.pose.yaw_deg;
      if (i > 0) {  // unwrap: the shortest way round from the previous frame
        const double previous = values_[i - 1][5];
        yaw = previous + std::remainder(yaw - previous, 360.0);
      }
      values_[i] = {p.pose.x_m, p.pose.y_m, p.pose.z_m, p.pose.roll_deg, p.pose.pitch_deg, yaw};
    }
    for (std::size_t i = 0; i < n; ++i) {
      const bool stop =
          (i > 0 && values_[i] == values_[i - 1]) || (i + 1 < n && values_[i] == values_[i + 1]);
      const std::size_t lo = i == 0 ? 0 : i - 1;
      const std::size_t hi = i + 1 == n ? i : i + 1;
      for (int c = 0; c < kChannels; ++c) {
        const auto k = static_cast<std::size_t>(c);
        tangents_[i][k] =
            stop ? 0.0 : (values_[hi][k] - values_[lo][k]) / (times_[hi] - times_[lo]);
      }
    }
    return Status::Ok();
  }

  double start() const { return times_.front(); }
  double end() const { return times_.back(); }

  // Value, first and second time derivative of every channel at t (clamped to the run).
  // `segment` is a hint (the last segment used) for a forward walk; it is updated.
  void Evaluate(double t, std::size_t* segment, std::array<double, kChannels>* v,
                std::array<double, kChannels>* d1, std::array<double, kChannels>* d2) const {
    t = std::clamp(t, start(), end());
    std::size_t i = std::min(*segment, times_.size() - 2);
    if (times_[i] > t)
      i = 0;
    while (i + 2 < times_.size() && times_[i + 1] <= t)
      ++i;
    *segment = i;
    const double h = times_[i + 1] - times_[i];
    const double s = (t - times_[i]) / h;
    const double s2 = s * s, s3 = s2 * s;
    const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2,
                 h11 = s3 - s2;
    const double d00 = 6 * s2 - 6 * s, d10 = 3 * s2 - 4 * s + 1, d01 = -d00, d11 = 3 * s2 - 2 * s;
    const double e00 = 12 * s - 6, e10 = 6 * s - 4, e01 = -e00, e11 = 6 * s - 2;
    for (std::size_t c = 0; c < kChannels; ++c) {
      const double p0 = values_[i][c], p1 = values_[i + 1][c];
      const double m0 = tangents_[i][c] * h, m1 = tangents_[i + 1][c] * h;
      (*v)[c] = h00 * p0 + h10 * m0 + h01 * p1 + h11 * m1;
      (*d1)[c] = (d00 * p0 + d10 * m0 + d01 * p1 + d11 * m1) / h;
      (*d2)[c] = (e00 * p0 + e10 * m0 + e01 * p1 + e11 * m1) / (h * h);
    }
  }

 private:
  std::vector<double> times_;
  std::vector<std::array<double, kChannels>> values_;
  std::vector<std::array<double, kChannels>> tangents_;
};

// Specific force and body rate from the spline's value and derivatives.
void Readings(const std::array<double, kChannels>& v, const std::array<double, kChannels>& d1,
              const std::array<double, kChannels>& d2, double gravity, Vec* force, Vec* rate) {
  const double roll = v[3] * dsp::kDegToRad, pitch = v[4] * dsp::kDegToRad,
               yaw = v[5] * dsp::kDegToRad;
  const double cy = std::cos(yaw), sy = std::sin(yaw);
  const double cp = std::cos(-pitch), sp = std::sin(-pitch);
  const double cr = std::cos(roll), sr = std::sin(roll);
  // R = Rz(yaw) Ry(-pitch) Rx(roll), the renderer's BodyToWorld.
  const double r[3][3] = {
      {cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr},
      {sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr},
      {-sp, cp * sr, cp * cr},
  };
  const Vec world{d2[0], d2[1], d2[2] + gravity};
  for (std::size_t j = 0; j < 3; ++j)
    (*force)[j] = r[0][j] * world[0] + r[1][j] * world[1] + r[2][j] * world[2];
  // w = roll' x + pitch' (0, -cos roll, sin roll) + yaw' up, with up = R^T z.
  const double droll = d1[3] * dsp::kDegToRad, dpitch = d1[4] * dsp::kDegToRad,
               dyaw = d1[5] * dsp::kDegToRad;
  *rate = {droll + dyaw * r[2][0], -dpitch * cr + dyaw * r[2][1], dpitch * sr + dyaw * r[2][2]};
}

Status ValidateConfig(const ImuModelConfig& c) {
  if (!(c.rate_hz >= 1 && c.rate_hz <= 100000))
    return Status::Error(StatusCode::kInvalidArgument,
                         "IMU model: rate %.3f Hz is outside 1..100000 Hz", c.rate_hz);
  const double values[] = {c.accel_noise_density, c.gyro_noise_density, c.accel_bias_walk,
                           c.gyro_bias_walk};
  for (const double v : values) {
    if (!(v >= 0 && std::isfinite(v)))
      return Status::Error(StatusCode::kInvalidArgument,
                           "IMU model: noise densities and bias walks must be finite and >= 0");
  }
  for (std::size_t i = 0; i < 3; ++i) {
    if (!std::isfinite(c.accel_bias_mps2[i]) || !std::isfinite(c.gyro_bias_radps[i]))
      return Status::Error(StatusCode::kInvalidArgument, "IMU model: biases must be finite");
  }
  if (!(c.gravity_mps2 > 0 && c.gravity_mps2 < 100))
    return Status::Error(StatusCode::kInvalidArgument,
                         "IMU model: gravity %.3f m/s^2 is outside 0..100", c.gravity_mps2);
  return Status::Ok();
}

std::int64_t ToNs(double t_s) {
  return std::llround(t_s * 1e9);
}

}  // namespace

ImuModelConfig IdealImu(double rate_hz) {
  ImuModelConfig c;
  c.rate_hz = rate_hz;
  c.accel_noise_density = 0;
  c.gyro_noise_density = 0;
  c.accel_bias_mps2 = {0, 0, 0};
  c.gyro_bias_radps = {0, 0, 0};
  c.accel_bias_walk = 0;
  c.gyro_bias_walk = 0;
  return c;
}

Status ImuTruthAt(std::span<const TrajectoryPoint> trajectory, double t, double gravity_mps2,
                  ImuTruth* out) {
  Spline spline;
  SKYLOC_TRY(spline.Build(trajectory));
  std::size_t segment = 0;
  std::array<double, kChannels> v{}, d1{}, d2{};
  spline.Evaluate(t, &segment, &v, &d1, &d2);
  out->pose = {v[0], v[1], v[2], v[3], v[4], v[5]};
  Readings(v, d1, d2, gravity_mps2, &out->specific_force_mps2, &out->gyro_radps);
  return Status::Ok();
}

Status SimulateImu(std::span<const TrajectoryPoint> trajectory, const ImuModelConfig& config,
                   std::vector<dsp::ImuSample>* out) {
  SKYLOC_TRY(ValidateConfig(config));
  Spline spline;
  SKYLOC_TRY(spline.Build(trajectory));
  const double duration = spline.end() - spline.start();
  const double count = std::floor(duration * config.rate_hz + 1e-6) + 1;
  if (count > 1e8)
    return Status::Error(StatusCode::kInvalidArgument,
                         "IMU model: %.0f samples (%.0f s at %.0f Hz) is more than 10^8", count,
                         duration, config.rate_hz);
  const auto n = static_cast<std::size_t>(count);
  out->clear();
  out->reserve(n);
  Rng rng(config.seed * 0x9E3779B97F4A7C15ull + 0x1A2B3C4D5E6Full);
  const double dt = 1.0 / config.rate_hz;
  const double accel_sigma = config.accel_noise_density * std::sqrt(config.rate_hz);
  const double gyro_sigma = config.gyro_noise_density * std::sqrt(config.rate_hz);
  const double accel_step = config.accel_bias_walk * std::sqrt(dt);
  const double gyro_step = config.gyro_bias_walk * std::sqrt(dt);
  Vec accel_walk{0, 0, 0}, gyro_walk{0, 0, 0};
  const std::int64_t start_ns = ToNs(spline.start());
  std::size_t segment = 0;
  std::array<double, kChannels> v{}, d1{}, d2{};
  for (std::size_t k = 0; k < n; ++k) {
    const double kd = static_cast<double>(k);
    const double t = spline.start() + kd * dt;
    spline.Evaluate(t, &segment, &v, &d1, &d2);
    Vec force, rate;
    Readings(v, d1, d2, config.gravity_mps2, &force, &rate);
    dsp::ImuSample s;
    s.timestamp_ns = start_ns + std::llround(kd * 1e9 / config.rate_hz);
    for (std::size_t i = 0; i < 3; ++i) {
      const double noise = accel_sigma > 0 ? accel_sigma * rng.Normal() : 0.0;
      s.accel_mps2[i] =
          static_cast<float>(force[i] + config.accel_bias_mps2[i] + accel_walk[i] + noise);
      if (accel_step > 0)
        accel_walk[i] += accel_step * rng.Normal();
    }
    for (std::size_t i = 0; i < 3; ++i) {
      const double noise = gyro_sigma > 0 ? gyro_sigma * rng.Normal() : 0.0;
      s.gyro_radps[i] =
          static_cast<float>(rate[i] + config.gyro_bias_radps[i] + gyro_walk[i] + noise);
      if (gyro_step > 0)
        gyro_walk[i] += gyro_step * rng.Normal();
    }
    out->push_back(s);
  }
  return Status::Ok();
}

Status EstimateAttitudes(std::span<const TrajectoryPoint> trajectory, const ImuModelConfig& imu,
                         const dsp::AttitudeFilterParams& filter,
                         std::vector<dsp::Attitude>* at_frames) {
  std::vector<dsp::ImuSample> samples;
  SKYLOC_TRY(SimulateImu(trajectory, imu, &samples));
  dsp::AttitudeFilter f;
  if (const dsp::AttitudeError e = f.Init(filter); e != dsp::AttitudeError::kOk)
    return drivers::DspStatus(e, "attitude filter");
  at_frames->assign(trajectory.size(), dsp::Attitude{});
  std::size_t next = 0;
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    const std::int64_t frame_ns = ToNs(trajectory[i].time_s);
    for (; next < samples.size() && samples[next].timestamp_ns <= frame_ns; ++next) {
      const dsp::AttitudeError e = f.Update(samples[next]);
      if (e != dsp::AttitudeError::kOk && e != dsp::AttitudeError::kGap)
        return drivers::DspStatus(e, "attitude filter, IMU sample %zu", next);
    }
    (*at_frames)[i] = f.attitude();
  }
  return Status::Ok();
}

AttitudeErrorStats CompareAttitudes(std::span<const TrajectoryPoint> trajectory,
                                    std::span<const dsp::Attitude> estimates) {
  AttitudeErrorStats s;
  const std::size_t n = std::min(trajectory.size(), estimates.size());
  if (n == 0)
    return s;
  double roll2 = 0, pitch2 = 0, tilt2 = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const drivers::Pose& p = trajectory[i].pose;
    const dsp::Attitude& e = estimates[i];
    const double dr = std::abs(std::remainder(e.roll_deg - p.roll_deg, 360.0));
    const double dp = std::abs(e.pitch_deg - p.pitch_deg);
    const Vec u = dsp::UpFromRollPitch(p.roll_deg, p.pitch_deg);
    const Vec c{u[1] * e.up[2] - u[2] * e.up[1], u[2] * e.up[0] - u[0] * e.up[2],
                u[0] * e.up[1] - u[1] * e.up[0]};
    const double dt = std::atan2(std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]),
                                 u[0] * e.up[0] + u[1] * e.up[1] + u[2] * e.up[2]) /
                      dsp::kDegToRad;
    roll2 += dr * dr;
    pitch2 += dp * dp;
    tilt2 += dt * dt;
    s.roll_max_deg = std::max(s.roll_max_deg, dr);
    s.pitch_max_deg = std::max(s.pitch_max_deg, dp);
    s.tilt_max_deg = std::max(s.tilt_max_deg, dt);
  }
  const double nd = static_cast<double>(n);
  s.roll_rms_deg = std::sqrt(roll2 / nd);
  s.pitch_rms_deg = std::sqrt(pitch2 / nd);
  s.tilt_rms_deg = std::sqrt(tilt2 / nd);
  return s;
}

}  // namespace skyloc::sim
