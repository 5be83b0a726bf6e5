#include "skyloc/dsp/zenith_estimate.h"

#include <Eigen/Eigenvalues>
#include <array>
#include <cmath>

#include "skyloc/dsp/angles.h"

namespace skyloc::dsp {
namespace {

// Fewer skyline crossings (or less sky, in sample weight) than this: no estimate.
constexpr int kMinCrossings = 8;
constexpr double kMinSkyWeight = 1e-3;

bool Normalise(std::array<double, 3>* v) {
  const double n = std::sqrt((*v)[0] * (*v)[0] + (*v)[1] * (*v)[1] + (*v)[2] * (*v)[2]);
  if (!(n > 0) || !std::isfinite(n))
    return false;
  for (double& x : *v)
    x /= n;
  return true;
}

}  // namespace

bool ZenithEstimator::Init(const ShGrid& grid, const ZenithEstimateOptions& options) {
  if (!grid.initialised() || options.iterations < 1 || options.iterations > 10 ||
      !(options.cone_deg >= 10 && options.cone_deg <= 90) ||
      !(options.max_tilt_deg >= 0 && options.max_tilt_deg <= 90))
    return false;
  options_ = options;
  rings_ = grid.ring_count();
  n_phi_ = grid.longitudes();
  cos_phi_.resize(static_cast<std::size_t>(n_phi_));
  sin_phi_.resize(static_cast<std::size_t>(n_phi_));
  for (int j = 0; j < n_phi_; ++j) {
    cos_phi_[static_cast<std::size_t>(j)] = std::cos(grid.phi(j));
    sin_phi_[static_cast<std::size_t>(j)] = std::sin(grid.phi(j));
  }
  ring_theta_.resize(static_cast<std::size_t>(rings_));
  ring_weight_.resize(static_cast<std::size_t>(rings_));
  for (int i = 0; i < rings_; ++i) {
    ring_theta_[static_cast<std::size_t>(i)] = grid.ring(i).theta;
    ring_weight_[static_cast<std::size_t>(i)] = grid.ring(i).weight;
  }
  return true;
}

bool ZenithEstimator::Estimate(std::span<const float> samples, std::int64_t timestamp_ns,
                               Attitude* out) const {
  if (rings_ == 0 ||
      samples.size() != static_cast<std::size_t>(rings_) * static_cast<std::size_t>(n_phi_))
    return false;
  std::array<double, 3> up{0, 0, 1};
  const bool ok = options_.method == ZenithMethod::kSkylinePlane ? SkylinePlane(samples, &up)
                                                                 : SkyCentroid(samples, &up);
  if (!ok || up[2] < std::cos(options_.max_tilt_deg * kDegToRad))
    return false;
  *out = AttitudeFromUp(timestamp_ns, up);
  return true;
}

bool ZenithEstimator::SkylinePlane(std::span<const float> samples,
                                   std::array<double, 3>* up) const {
  const auto n_phi = static_cast<std::size_t>(n_phi_);
  double s0 = 0;
  Eigen::Vector3d s1 = Eigen::Vector3d::Zero();
  Eigen::Matrix3d s2 = Eigen::Matrix3d::Zero();
  int crossings = 0;
  for (std::size_t j = 0; j < n_phi; ++j) {
    for (std::size_t i = 0; i + 1 < static_cast<std::size_t>(rings_); ++i) {
      const auto a = static_cast<double>(samples[i * n_phi + j]);
      const auto b = static_cast<double>(samples[(i + 1) * n_phi + j]);
      const bool sky_to_ground = a >= 0.5 && b < 0.5;
      if (!sky_to_ground && !(a < 0.5 && b >= 0.5))
        continue;
      if (options_.first_crossing_only && !sky_to_ground)
        continue;
      // Where the sample value crosses 0.5 between the two rings.
      const double t = (a - 0.5) / (a - b);
      const double theta = ring_theta_[i] + t * (ring_theta_[i + 1] - ring_theta_[i]);
      const double st = std::sin(theta);
      const Eigen::Vector3d d(st * cos_phi_[j], st * sin_phi_[j], std::cos(theta));
      const double w = st;  // length along the skyline per longitude step
      s0 += w;
      s1 += w * d;
      s2 += w * d * d.transpose();
      ++crossings;
      if (options_.first_crossing_only)
        break;
    }
  }
  if (crossings < kMinCrossings || !(s0 > 0))
    return false;
  const Eigen::Vector3d mean = s1 / s0;
  const Eigen::Matrix3d covariance = s2 / s0 - mean * mean.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(covariance);
  if (solver.info() != Eigen::Success)
    return false;
  // Eigenvalues ascending: the plane's normal is the first eigenvector.
  Eigen::Vector3d n = solver.eigenvectors().col(0);
  if (n(2) < 0)
    n = -n;
  *up = {n(0), n(1), n(2)};
  return Normalise(up);
}

bool ZenithEstimator::SkyCentroid(std::span<const float> samples, std::array<double, 3>* up) const {
  const auto n_phi = static_cast<std::size_t>(n_phi_);
  const double cos_cone = std::cos(options_.cone_deg * kDegToRad);
  std::array<double, 3> u{0, 0, 1};
  for (int pass = 0; pass < options_.iterations; ++pass) {
    std::array<double, 3> sum{0, 0, 0};
    double weight = 0;
    for (std::size_t i = 0; i < static_cast<std::size_t>(rings_); ++i) {
      const double st = std::sin(ring_theta_[i]);
      const double ct = std::cos(ring_theta_[i]);
      const float* ring = samples.data() + i * n_phi;
      for (std::size_t j = 0; j < n_phi; ++j) {
        if (ring[j] <= 0.0f)
          continue;
        const double x = st * cos_phi_[j], y = st * sin_phi_[j];
        if (x * u[0] + y * u[1] + ct * u[2] < cos_cone)
          continue;
        const double w = ring_weight_[i] * static_cast<double>(ring[j]);
        sum[0] += w * x;
        sum[1] += w * y;
        sum[2] += w * ct;
        weight += w;
      }
    }
    if (weight < kMinSkyWeight || !Normalise(&sum))
      return false;
    u = sum;
  }
  *up = u;
  return true;
}

}  // namespace skyloc::dsp
