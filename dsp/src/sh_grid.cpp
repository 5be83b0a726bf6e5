#include "skyloc/dsp/sh_grid.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace skyloc::dsp {

const char* ShErrorMessage(ShError error) {
  switch (error) {
    case ShError::kOk:
      return "ok";
    case ShError::kRingsOutOfRange:
      return "the SH grid's ring count is outside 1..1024; use at least bands/2 rings";
    case ShError::kLongitudesOutOfRange:
      return "the SH grid's longitudes per ring are outside 4..8192; use at least 2*bands";
    case ShError::kBandsOutOfRange:
      return "the SH band count is outside 1..512; 120 is the usual value";
    case ShError::kTableTooLarge:
      return "the naive SH projector's table (bands^2 x samples floats) exceeds 256 MB; use "
             "fewer bands or samples, or the fast projector";
    case ShError::kLongitudesNotPowerOfTwo:
      return "the SH grid's longitudes per ring must be a power of two (e.g. 128, 256, 512) for "
             "the ring FFT";
    case ShError::kNotInitialised:
      return "the SH grid or projector was used before a successful Init()";
    case ShError::kSizeMismatch:
      return "an SH buffer's size does not match the grid's sample count or bands^2";
  }
  return "unknown SH error";
}

ShError ValidateShGridConfig(const ShGridConfig& config) {
  if (config.rings < 1 || config.rings > kMaxShRings)
    return ShError::kRingsOutOfRange;
  if (config.longitudes < 4 || config.longitudes > kMaxShLongitudes)
    return ShError::kLongitudesOutOfRange;
  if ((config.longitudes & (config.longitudes - 1)) != 0)
    return ShError::kLongitudesNotPowerOfTwo;
  return ShError::kOk;
}

ShGridConfig DefaultShGridConfig(int bands) {
  bands = std::clamp(bands, 1, kMaxShBands);
  ShGridConfig config;
  config.rings = (bands + 1) / 2;
  int longitudes = 4;
  while (longitudes < 2 * bands - 1)
    longitudes *= 2;
  config.longitudes = longitudes;
  config.coverage = ShCoverage::kUpperHemisphere;
  return config;
}

ShGridConfig OversampledShGridConfig(int bands) {
  bands = std::clamp(bands, 1, kMaxShBands);
  return DefaultShGridConfig((3 * bands + 1) / 2);
}

ShGridConfig PaperShGridConfig() {
  return ShGridConfig{.rings = 16, .longitudes = 128, .coverage = ShCoverage::kUpperHemisphere};
}

bool ShGridResolvesBands(const ShGridConfig& config, int bands) {
  // An n-node Gauss–Legendre rule integrates polynomials of degree ≤ 2n-1 exactly; the
  // product P̄_lm·P̄_l'm' has degree l + l' ≤ 2·bands - 2. cos(mφ)cos(m'φ) sums exactly over
  // `longitudes` equispaced points when m + m' < longitudes.
  const int nodes =
      config.coverage == ShCoverage::kUpperHemisphere ? 2 * config.rings : config.rings;
  return nodes >= bands && config.longitudes >= 2 * bands - 1;
}

bool GaussLegendreNodes(int n, std::span<double> nodes, std::span<double> weights) {
  if (n < 1 || nodes.size() < static_cast<std::size_t>(n) ||
      weights.size() < static_cast<std::size_t>(n))
    return false;
  const double nd = n;
  for (int k = 1; k <= (n + 1) / 2; ++k) {
    // Tricomi's estimate of the k-th largest root, then Newton on P_n.
    double x = std::cos(std::numbers::pi * (k - 0.25) / (nd + 0.5));
    double derivative = 0;
    for (int iteration = 0; iteration < 100; ++iteration) {
      double p_prev = 1.0;
      double p = x;
      for (int j = 2; j <= n; ++j) {
        const double p_next = ((2.0 * j - 1.0) * x * p - (j - 1.0) * p_prev) / j;
        p_prev = p;
        p = p_next;
      }
      derivative = nd * (x * p - p_prev) / (x * x - 1.0);
      const double step = p / derivative;
      x -= step;
      if (std::fabs(step) < 1e-15)
        break;
    }
    // Recompute the derivative at the converged root for the weight.
    {
      double p_prev = 1.0;
      double p = x;
      for (int j = 2; j <= n; ++j) {
        const double p_next = ((2.0 * j - 1.0) * x * p - (j - 1.0) * p_prev) / j;
        p_prev = p;
        p = p_next;
      }
      derivative = nd * (x * p - p_prev) / (x * x - 1.0);
    }
    if (2 * k - 1 == n)
      x = 0.0;  // the middle node of an odd rule is exactly the equator
    const double w = 2.0 / ((1.0 - x * x) * derivative * derivative);
    const auto upper = static_cast<std::size_t>(k - 1);
    const auto lower = static_cast<std::size_t>(n - k);
    nodes[upper] = x;
    nodes[lower] = -x;
    weights[upper] = w;
    weights[lower] = w;
  }
  return true;
}

ShError ShGrid::Init(const ShGridConfig& config) {
  rings_.clear();
  if (const ShError e = ValidateShGridConfig(config); e != ShError::kOk)
    return e;
  const int nodes =
      config.coverage == ShCoverage::kUpperHemisphere ? 2 * config.rings : config.rings;
  std::vector<double> x(static_cast<std::size_t>(nodes));
  std::vector<double> w(static_cast<std::size_t>(nodes));
  GaussLegendreNodes(nodes, x, w);
  config_ = config;
  rings_.resize(static_cast<std::size_t>(config.rings));
  const double phi_weight = 2.0 * std::numbers::pi / config.longitudes;
  for (std::size_t i = 0; i < rings_.size(); ++i) {
    ShRing& r = rings_[i];
    r.cos_theta = x[i];
    r.sin_theta = std::sqrt((1.0 - x[i]) * (1.0 + x[i]));
    r.theta = std::acos(x[i]);
    r.weight = w[i] * phi_weight;
  }
  return ShError::kOk;
}

double ShGrid::phi(int j) const {
  return 2.0 * std::numbers::pi * j / config_.longitudes;
}

ShDirection ShGrid::direction(std::size_t sample) const {
  const auto n = static_cast<std::size_t>(config_.longitudes);
  const ShRing& r = rings_[sample / n];
  ShDirection d;
  d.theta = r.theta;
  d.phi = phi(static_cast<int>(sample % n));
  d.x = r.sin_theta * std::cos(d.phi);
  d.y = r.sin_theta * std::sin(d.phi);
  d.z = r.cos_theta;
  return d;
}

}  // namespace skyloc::dsp
