#include "skyloc/dsp/spherical_harmonics.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <boost/math/special_functions/spherical_harmonic.hpp>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "skyloc/dsp/legendre.h"
#include "skyloc/platform/alloc_counter.h"
#include "support/angles.h"

namespace skyloc::dsp {
namespace {

ShGrid MakeGrid(const ShGridConfig& config) {
  ShGrid grid;
  EXPECT_EQ(grid.Init(config), ShError::kOk);
  return grid;
}

std::vector<double> RealSh(int bands, double theta, double phi) {
  std::vector<double> scratch(LegendreTriangleSize(bands)), y(ShCoefficientCount(bands));
  EXPECT_TRUE(RealSphericalHarmonics(bands, std::cos(theta), std::sin(theta), phi, scratch, y));
  return y;
}

// --- The basis ---------------------------------------------------------------------------

// Reference: Boost.Math's complex Y_l^m (Condon–Shortley phase) turned into the paper's real
// basis: √2·Re Y_l^m for m > 0, √2·Im Y_l^|m| for m < 0, Y_l^0 for m = 0. Absolute tolerance
// 1e-10 on values of size up to ~3.
TEST(RealSphericalHarmonics, MatchBoostInTheRealBasisUpToL120) {
  if (std::numeric_limits<long double>::digits <= std::numeric_limits<double>::digits) {
    GTEST_SKIP() << "Boost's reference is only more precise than this code with a long double "
                    "wider than double; on this target (e.g. armhf) they are the same type";
  }
  constexpr int kBands = 121;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> theta_dist(0.0, kPi), phi_dist(0.0, 2 * kPi);
  for (int trial = 0; trial < 3; ++trial) {
    const double theta = theta_dist(rng), phi = phi_dist(rng);
    const std::vector<double> y = RealSh(kBands, theta, phi);
    for (int l = 0; l < kBands; ++l) {
      for (int m = -l; m <= l; ++m) {
        const auto ul = static_cast<unsigned>(l);
        double ref = 0;
        if (m > 0)
          ref = std::sqrt(2.0) * boost::math::spherical_harmonic_r(ul, m, theta, phi);
        else if (m < 0)
          ref = std::sqrt(2.0) * boost::math::spherical_harmonic_i(ul, -m, theta, phi);
        else
          ref = boost::math::spherical_harmonic_r(ul, 0, theta, phi);
        ASSERT_NEAR(y[ShIndex(l, m)], ref, 1e-10) << "l=" << l << " m=" << m;
      }
    }
  }
}

TEST(RealSphericalHarmonics, IndexLayoutAndLowOrderFormulas) {
  EXPECT_EQ(ShIndex(0, 0), 0u);
  EXPECT_EQ(ShIndex(1, -1), 1u);
  EXPECT_EQ(ShIndex(1, 1), 3u);
  EXPECT_EQ(ShIndex(2, -2), 4u);
  EXPECT_EQ(ShCoefficientCount(120), 14400u);
  // Closed forms with the Condon–Shortley phase: y_1,1 = -sqrt(3/4π)·x, y_1,-1 = -sqrt(3/4π)·y.
  const double theta = 1.1, phi = 0.4;
  const std::vector<double> y = RealSh(3, theta, phi);
  const double k = std::sqrt(3 / (4 * kPi));
  EXPECT_NEAR(y[ShIndex(0, 0)], 1 / std::sqrt(4 * kPi), 1e-15);
  EXPECT_NEAR(y[ShIndex(1, 0)], k * std::cos(theta), 1e-15);
  EXPECT_NEAR(y[ShIndex(1, 1)], -k * std::sin(theta) * std::cos(phi), 1e-15);
  EXPECT_NEAR(y[ShIndex(1, -1)], -k * std::sin(theta) * std::sin(phi), 1e-15);
}

// Orthonormality, directly: the full-sphere grid's quadrature Σ_s w_s y_k(s) y_k'(s) is the
// identity for every pair k, k' with l, l' < 14 (all L^4 pairs, double precision).
TEST(RealSphericalHarmonics, FullSphereQuadratureIsOrthonormalAllPairs) {
  constexpr int kBands = 14;
  const ShGrid grid =
      MakeGrid({.rings = kBands, .longitudes = 32, .coverage = ShCoverage::kFullSphere});
  const auto n = static_cast<Eigen::Index>(grid.sample_count());
  const auto k = static_cast<Eigen::Index>(ShCoefficientCount(kBands));
  Eigen::MatrixXd y(k, n);
  for (Eigen::Index s = 0; s < n; ++s) {
    const ShDirection d = grid.direction(static_cast<std::size_t>(s));
    const double w = grid.ring(static_cast<int>(s / grid.longitudes())).weight;
    const std::vector<double> v = RealSh(kBands, d.theta, d.phi);
    for (Eigen::Index i = 0; i < k; ++i)
      y(i, s) = v[static_cast<std::size_t>(i)] * std::sqrt(w);
  }
  const Eigen::MatrixXd gram = y * y.transpose();
  EXPECT_LT((gram - Eigen::MatrixXd::Identity(k, k)).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LT((gram - Eigen::MatrixXd::Identity(k, k)).cwiseAbs().maxCoeff(), 1e-12);
}

// Orthonormality at L = 120 on the 120-ring × 256 full-sphere grid, by its two factors
// (y_lm is separable): the latitude sums Σ_i w_i·P̄_lm·P̄_l'm = δ_ll'/(2π) for every m, and
// the longitude sums of cos/sin(mφ)·cos/sin(m'φ) over 256 points = π·δ_mm' (2π for m = 0).
TEST(RealSphericalHarmonics, FullSphereQuadratureIsOrthonormalAtL120) {
  constexpr int kBands = 120;
  const ShGrid grid =
      MakeGrid({.rings = kBands, .longitudes = 256, .coverage = ShCoverage::kFullSphere});
  std::vector<std::vector<double>> p;
  for (const ShRing& r : grid.rings()) {
    p.emplace_back(LegendreTriangleSize(kBands));
    ASSERT_TRUE(NormalisedLegendre(kBands, r.cos_theta, r.sin_theta, p.back()));
  }
  // Latitude: for each m, Σ_i (w_i·n/2π)·P̄_lm(x_i)·P̄_l'm(x_i) must be δ_ll'/(2π) (the ring
  // weight without its 2π/n longitude factor). Plain loops: fast in Debug builds too.
  const double ring_sum_to_integral = grid.longitudes() / (2 * kPi);
  const auto rings = static_cast<std::size_t>(grid.ring_count());
  std::vector<double> pm(rings * kBands);  // row l: the rings' scaled P̄_lm
  double worst = 0;
  for (int m = 0; m < kBands; ++m) {
    for (int l = m; l < kBands; ++l)
      for (std::size_t i = 0; i < rings; ++i)
        pm[static_cast<std::size_t>(l) * rings + i] =
            std::sqrt(grid.rings()[i].weight * ring_sum_to_integral) * p[i][LegendreIndex(l, m)];
    for (int l = m; l < kBands; ++l) {
      for (int l2 = l; l2 < kBands; ++l2) {
        const double* a = &pm[static_cast<std::size_t>(l) * rings];
        const double* b = &pm[static_cast<std::size_t>(l2) * rings];
        double sum = 0;
        for (std::size_t i = 0; i < rings; ++i)
          sum += a[i] * b[i];
        worst = std::max(worst, std::fabs(2 * kPi * sum - (l == l2 ? 1.0 : 0.0)));
      }
    }
  }
  EXPECT_LT(worst, 1e-12);
  // Longitude: rows cos(mφ_j) and sin(mφ_j) for m < L; the sums of their products over the
  // n points, times 2π/n, must be π·δ (2π for the cos m = 0 row, sin 0 is identically 0).
  const int n = grid.longitudes();
  Eigen::MatrixXd trig(2 * kBands - 1, n);
  for (int j = 0; j < n; ++j) {
    for (int m = 0; m < kBands; ++m) {
      trig(m, j) = std::cos(m * grid.phi(j));
      if (m > 0)
        trig(kBands + m - 1, j) = std::sin(m * grid.phi(j));
    }
  }
  Eigen::MatrixXd expected = kPi * Eigen::MatrixXd::Identity(2 * kBands - 1, 2 * kBands - 1);
  expected(0, 0) = 2 * kPi;
  const Eigen::MatrixXd sums = (2 * kPi / n) * trig * trig.transpose();
  EXPECT_LT((sums - expected).cwiseAbs().maxCoeff(), 1e-12);
}

// --- Fast projection against the naive reference ----------------------------------------

// Analytic skies: unions of spherical caps, evaluated directly at each grid direction.
struct Cap {
  Eigen::Vector3d centre;
  double radius;  // angular radius, radians
};

Eigen::Vector3d Unit(double theta, double phi) {
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

// Sky = union of `sky` caps minus union of `obstacles`; with `hemisphere`, the lower half of
// the camera's sphere is ground. `rotation` maps world directions into the camera frame, so
// the camera sees the world at R^T·d.
std::vector<float> SampleSky(const ShGrid& grid, const std::vector<Cap>& sky,
                             const std::vector<Cap>& obstacles, const Eigen::Matrix3d& rotation,
                             bool hemisphere) {
  // (Rᵀd)·c = d·(Rc): rotate the caps once instead of every direction.
  struct RotatedCap {
    double x, y, z, cos_radius;
  };
  auto rotate = [&](const std::vector<Cap>& caps) {
    std::vector<RotatedCap> out;
    for (const Cap& c : caps) {
      const Eigen::Vector3d r = rotation * c.centre;
      out.push_back({r.x(), r.y(), r.z(), std::cos(c.radius)});
    }
    return out;
  };
  const std::vector<RotatedCap> sky_caps = rotate(sky), obstacle_caps = rotate(obstacles);
  std::vector<float> f(grid.sample_count());
  for (std::size_t s = 0; s < f.size(); ++s) {
    const ShDirection d = grid.direction(s);
    bool in = false;
    for (const RotatedCap& c : sky_caps)
      in = in || d.x * c.x + d.y * c.y + d.z * c.z >= c.cos_radius;
    for (const RotatedCap& c : obstacle_caps)
      in = in && d.x * c.x + d.y * c.y + d.z * c.z < c.cos_radius;
    f[s] = (in && !(hemisphere && d.z <= 0)) ? 1.0f : 0.0f;
  }
  return f;
}

// Both projectors on one grid; every mask must give the same coefficients.
void ExpectFastEqualsNaive(const ShGridConfig& config, int bands,
                           const std::vector<std::pair<std::string, std::vector<float>>>& masks) {
  const ShGrid grid = MakeGrid(config);
  ShProjector fast;
  ShNaiveProjector naive;
  ASSERT_EQ(fast.Init(grid, bands), ShError::kOk);
  ASSERT_EQ(naive.Init(grid, bands), ShError::kOk);
  std::vector<float> a(ShCoefficientCount(bands)), b(a.size());
  for (const auto& [what, f] : masks) {
    ASSERT_EQ(fast.Project(f, a), ShError::kOk);
    ASSERT_EQ(naive.Project(f, b), ShError::kOk);
    float largest = 0, worst = 0;
    for (std::size_t k = 0; k < a.size(); ++k) {
      largest = std::max(largest, std::fabs(b[k]));
      worst = std::max(worst, std::fabs(a[k] - b[k]));
    }
    ASSERT_GT(largest, 0.0f) << what;
    // 1e-5 relative to the largest coefficient (float tables and FFT; typically ~1e-7).
    EXPECT_LT(worst, 1e-5f * largest) << config.rings << "x" << config.longitudes << " L=" << bands
                                      << " " << what << ": worst " << worst << " of " << largest;
  }
}

std::vector<float> RandomMask(const ShGridConfig& config, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<float> f(static_cast<std::size_t>(config.rings * config.longitudes));
  for (float& v : f)
    v = static_cast<float>(rng() & 1u);
  return f;
}

std::vector<float> StructuredMask(const ShGridConfig& config, int kind) {
  const ShGrid grid = MakeGrid(config);
  std::vector<float> f(grid.sample_count());
  for (std::size_t s = 0; s < f.size(); ++s) {
    const ShDirection d = grid.direction(s);
    switch (kind) {
      case 0:  // a tilted cap
        f[s] = Unit(0.5, 1.0).dot(Eigen::Vector3d(d.x, d.y, d.z)) > std::cos(0.7) ? 1.0f : 0.0f;
        break;
      case 1:  // longitude stripes (strong single-m content)
        f[s] = static_cast<int>(std::floor(d.phi / (2 * kPi) * 14)) % 2 == 0 ? 1.0f : 0.0f;
        break;
      default:  // latitude stripes (m = 0 only)
        f[s] = static_cast<int>(std::floor(d.theta * 12)) % 2 == 0 ? 1.0f : 0.0f;
        break;
    }
  }
  return f;
}

TEST(ShProjector, EqualsNaiveOnRandomAndStructuredMasks) {
  const std::vector<std::pair<ShGridConfig, int>> cases = {
      {DefaultShGridConfig(32), 32},
      {PaperShGridConfig(), 32},
      {{.rings = 8, .longitudes = 32}, 24},  // m > 16 folds past Nyquist (aliased in both)
      {{.rings = 5, .longitudes = 16}, 40},  // m wraps around the FFT length twice
      {{.rings = 25, .longitudes = 64, .coverage = ShCoverage::kFullSphere}, 30},
  };
  for (const auto& [config, bands] : cases) {
    ExpectFastEqualsNaive(config, bands,
                          {{"random", RandomMask(config, 5)},
                           {"tilted cap", StructuredMask(config, 0)},
                           {"longitude stripes", StructuredMask(config, 1)},
                           {"latitude stripes", StructuredMask(config, 2)}});
  }
}

// Projecting one basis function on the default grid returns its unit vector (a smooth
// function, so this checks the fast path's quadrature and its sign conventions at L = 120).
TEST(ShProjector, ProjectingABasisFunctionOnTheFullSphereGivesItsUnitVector) {
  constexpr int kBands = 120;
  const ShGrid grid =
      MakeGrid({.rings = kBands, .longitudes = 256, .coverage = ShCoverage::kFullSphere});
  ShProjector fast;
  ASSERT_EQ(fast.Init(grid, kBands), ShError::kOk);
  std::vector<float> f(grid.sample_count()), c(ShCoefficientCount(kBands));
  std::vector<std::vector<double>> legendre;
  for (const ShRing& r : grid.rings()) {
    legendre.emplace_back(LegendreTriangleSize(kBands));
    ASSERT_TRUE(NormalisedLegendre(kBands, r.cos_theta, r.sin_theta, legendre.back()));
  }
  for (const auto& [l, m] : {std::pair{0, 0}, {1, -1}, {60, 59}, {119, -119}, {90, 45}}) {
    // y_lm from eq. (1) directly: √2·P̄_l|m|·cos(mφ) or sin(|m|φ).
    for (std::size_t s = 0; s < f.size(); ++s) {
      const ShDirection d = grid.direction(s);
      const double p = legendre[s / 256][LegendreIndex(l, std::abs(m))];
      const double y = m == 0  ? p
                       : m > 0 ? std::sqrt(2.0) * p * std::cos(m * d.phi)
                               : std::sqrt(2.0) * p * std::sin(-m * d.phi);
      f[s] = static_cast<float>(y);
    }
    ASSERT_EQ(fast.Project(f, c), ShError::kOk);
    for (std::size_t k = 0; k < c.size(); ++k)
      ASSERT_NEAR(c[k], k == ShIndex(l, m) ? 1.0f : 0.0f, 2e-5f) << "l=" << l << " m=" << m;
  }
}

TEST(ShProjector, RejectsMisuse) {
  ShProjector fast;
  std::vector<float> f(10), c(4);
  EXPECT_EQ(fast.Project(f, c), ShError::kNotInitialised);
  ShGrid grid;
  EXPECT_EQ(fast.Init(grid, 4), ShError::kNotInitialised);
  grid = MakeGrid({.rings = 4, .longitudes = 8});
  EXPECT_EQ(fast.Init(grid, 0), ShError::kBandsOutOfRange);
  EXPECT_EQ(fast.Init(grid, kMaxShBands + 1), ShError::kBandsOutOfRange);
  ASSERT_EQ(fast.Init(grid, 2), ShError::kOk);
  EXPECT_EQ(fast.Project(f, c), ShError::kSizeMismatch);
  ShNaiveProjector naive;
  const ShGrid big = MakeGrid(DefaultShGridConfig(120));
  EXPECT_EQ(naive.Init(big, 120), ShError::kTableTooLarge);
}

TEST(ShProjector, ProjectAndAmplitudesAllocateNothing) {
  ASSERT_TRUE(AllocationCounterActive());
  for (const ShGridConfig& config : {DefaultShGridConfig(120), PaperShGridConfig()}) {
    const ShGrid grid = MakeGrid(config);
    ShProjector fast;
    ASSERT_EQ(fast.Init(grid, 120), ShError::kOk);
    const std::vector<float> f = RandomMask(config, 9);
    std::vector<float> c(fast.coefficient_count()), a(120);
    AllocationScope scope;
    for (int i = 0; i < 3; ++i) {
      ASSERT_EQ(fast.Project(f, c), ShError::kOk);
      ASSERT_EQ(AmplitudeSpectrum(c, 120, a, AmplitudeNormalisation::kUnitL2), ShError::kOk);
    }
    EXPECT_EQ(scope.allocations(), 0u);
  }
}

// --- Amplitudes and distances ------------------------------------------------------------

TEST(AmplitudeSpectrum, IsTheNormOfEachBand) {
  constexpr int kBands = 4;
  std::vector<float> c(ShCoefficientCount(kBands), 0.0f);
  c[ShIndex(0, 0)] = 2;
  c[ShIndex(1, -1)] = 3;
  c[ShIndex(1, 1)] = 4;
  c[ShIndex(3, -2)] = -1;
  std::vector<float> a(kBands);
  ASSERT_EQ(AmplitudeSpectrum(c, kBands, a), ShError::kOk);
  EXPECT_EQ(a, (std::vector<float>{2, 5, 0, 1}));
  ASSERT_EQ(AmplitudeSpectrum(c, kBands, a, AmplitudeNormalisation::kDivideByA0), ShError::kOk);
  EXPECT_EQ(a, (std::vector<float>{1, 2.5f, 0, 0.5f}));
  ASSERT_EQ(AmplitudeSpectrum(c, kBands, a, AmplitudeNormalisation::kUnitL2), ShError::kOk);
  EXPECT_NEAR(a[1], 5 / std::sqrt(30.0f), 1e-7f);
  std::fill(c.begin(), c.end(), 0.0f);
  ASSERT_EQ(AmplitudeSpectrum(c, kBands, a, AmplitudeNormalisation::kDivideByA0), ShError::kOk);
  EXPECT_EQ(a, (std::vector<float>{0, 0, 0, 0}));
  EXPECT_EQ(AmplitudeSpectrum(c, kBands + 1, a), ShError::kSizeMismatch);
}

TEST(AmplitudeSpectrum, SkyCapA0IsItsSolidAngleOverSqrt4Pi) {
  // a_0 = |c_00| = Ω/sqrt(4π) for a mask of solid angle Ω: the whole upper hemisphere has
  // Ω = 2π, and a zenith cap of radius α has Ω = 2π(1 - cos α).
  const ShGridConfig config = DefaultShGridConfig(120);
  const ShGrid grid = MakeGrid(config);
  ShProjector fast;
  ASSERT_EQ(fast.Init(grid, 120), ShError::kOk);
  std::vector<float> c(fast.coefficient_count()), a(120);
  const std::vector<float> sky(grid.sample_count(), 1.0f);
  ASSERT_EQ(fast.Project(sky, c), ShError::kOk);
  ASSERT_EQ(AmplitudeSpectrum(c, 120, a), ShError::kOk);
  EXPECT_NEAR(a[0], 2 * kPi / std::sqrt(4 * kPi), 1e-5);
  // ∫_upper y_10 = sqrt(3/4π)·π. Not exact on the grid: the equator cut is a discontinuity
  // of the integrand for the Gauss rule (error ~6e-5 relative with 120 nodes); a_0 above is
  // exact because the upper half of a symmetric rule carries exactly half the weight.
  EXPECT_NEAR(c[ShIndex(1, 0)], std::sqrt(3 / (4 * kPi)) * kPi, 2e-4);
}

TEST(DescriptorDistance, Metrics) {
  const std::vector<float> a{1, 2, 3}, b{2, 0, 3}, z{0, 0, 0};
  EXPECT_FLOAT_EQ(DescriptorDistance(a, b), 3.0f);
  EXPECT_FLOAT_EQ(DescriptorDistance(a, b, DescriptorMetric::kL2), std::sqrt(5.0f));
  EXPECT_NEAR(DescriptorDistance(a, b, DescriptorMetric::kCosine), 1 - 11 / std::sqrt(14.0 * 13.0),
              1e-7);
  EXPECT_FLOAT_EQ(DescriptorDistance(a, a, DescriptorMetric::kCosine), 0.0f);
  EXPECT_FLOAT_EQ(DescriptorDistance(z, z, DescriptorMetric::kCosine), 0.0f);
  EXPECT_FLOAT_EQ(DescriptorDistance(a, z, DescriptorMetric::kCosine), 1.0f);
  EXPECT_TRUE(std::isnan(DescriptorDistance(a, std::vector<float>{1, 2})));
}

// --- Invariance with analytic skies ------------------------------------------------------

Eigen::Matrix3d Yaw(double angle) {
  return Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}
Eigen::Matrix3d Tilt(double degrees) {
  return Eigen::AngleAxisd(degrees * kPi / 180, Eigen::Vector3d(std::cos(0.3), std::sin(0.3), 0))
      .toRotationMatrix();
}

// Two "places": an open sky crossed by tree crowns and a building edge.
const std::vector<Cap> kPlaceASky = {{Unit(0.1, 0.2), 1.25}, {Unit(1.2, 2.0), 0.35}};
const std::vector<Cap> kPlaceAObstacles = {
    {Unit(0.9, 0.5), 0.45}, {Unit(0.7, 3.0), 0.3}, {Unit(1.1, 4.4), 0.5}, {Unit(0.35, 5.5), 0.15}};
const std::vector<Cap> kPlaceBSky = {{Unit(0.2, 4.0), 1.1}, {Unit(1.0, 0.8), 0.4}};
const std::vector<Cap> kPlaceBObstacles = {
    {Unit(0.8, 1.9), 0.35}, {Unit(0.6, 5.0), 0.4}, {Unit(1.2, 3.3), 0.45}};

class Describer {
 public:
  Describer(const ShGridConfig& config, int bands) : grid_(MakeGrid(config)), bands_(bands) {
    EXPECT_EQ(projector_.Init(grid_, bands), ShError::kOk);
    c_.resize(ShCoefficientCount(bands));
  }
  std::vector<float> Amplitudes(const std::vector<Cap>& sky, const std::vector<Cap>& obstacles,
                                const Eigen::Matrix3d& rotation, bool hemisphere) {
    const std::vector<float> f = SampleSky(grid_, sky, obstacles, rotation, hemisphere);
    std::vector<float> a(static_cast<std::size_t>(bands_));
    EXPECT_EQ(projector_.Project(f, c_), ShError::kOk);
    EXPECT_EQ(AmplitudeSpectrum(c_, bands_, a), ShError::kOk);
    return a;
  }

 private:
  ShGrid grid_;
  int bands_;
  ShProjector projector_;
  std::vector<float> c_;
};

double RelativeL2(const std::vector<float>& a, const std::vector<float>& b) {
  const std::vector<float> zero(a.size(), 0.0f);
  return DescriptorDistance(a, b, DescriptorMetric::kL2) /
         DescriptorDistance(a, zero, DescriptorMetric::kL2);
}

TEST(ShInvariance, YawChangesAmplitudesByLessThanOnePercent) {
  Describer describer(DefaultShGridConfig(120), 120);
  const auto a = describer.Amplitudes(kPlaceASky, kPlaceAObstacles, Yaw(0), true);
  for (double yaw : {0.37, 1.9, 4.3}) {
    const auto b = describer.Amplitudes(kPlaceASky, kPlaceAObstacles, Yaw(yaw), true);
    std::printf("yaw %.2f rad: relative L2 amplitude change %.3g\n", yaw, RelativeL2(a, b));
    EXPECT_LT(RelativeL2(a, b), 0.01) << "yaw " << yaw;
  }
  const auto other = describer.Amplitudes(kPlaceBSky, kPlaceBObstacles, Yaw(0), true);
  EXPECT_GT(RelativeL2(a, other), 0.05) << "two different places must not look alike";
}

TEST(ShInvariance, FullSphereTiltOf60DegreesChangesAmplitudesByLessThanTwoPercent) {
  Describer describer({.rings = 120, .longitudes = 256, .coverage = ShCoverage::kFullSphere}, 120);
  const auto a = describer.Amplitudes(kPlaceASky, kPlaceAObstacles, Tilt(0), false);
  const auto b = describer.Amplitudes(kPlaceASky, kPlaceAObstacles, Tilt(60), false);
  std::printf("full sphere, tilt 60 deg: relative L2 amplitude change %.5f\n", RelativeL2(a, b));
  EXPECT_LT(RelativeL2(a, b), 0.02);
}

TEST(ShInvariance, HemisphereTiltReportedNextToADifferentPlace) {
  Describer describer(DefaultShGridConfig(120), 120);
  const auto a = describer.Amplitudes(kPlaceASky, kPlaceAObstacles, Tilt(0), true);
  const auto other = describer.Amplitudes(kPlaceBSky, kPlaceBObstacles, Tilt(0), true);
  const double place_distance = RelativeL2(a, other);
  std::printf("hemisphere, relative L2 amplitude change (L=120, 60x256 grid):\n");
  std::printf("  different place: %.4f\n", place_distance);
  double previous = 0;
  for (double tilt : {10.0, 20.0, 40.0, 60.0}) {
    const double change =
        RelativeL2(a, describer.Amplitudes(kPlaceASky, kPlaceAObstacles, Tilt(tilt), true));
    std::printf("  tilt %2.0f deg:      %.4f\n", tilt, change);
    // Sanity only: tilting changes the view, more tilt does not make it identical again.
    EXPECT_GT(change, 0.0);
    EXPECT_LT(change, 1.0);
    if (tilt <= 20.0) {
      EXPECT_GT(change, previous * 0.5);
    }
    previous = change;
  }
}

}  // namespace
}  // namespace skyloc::dsp
