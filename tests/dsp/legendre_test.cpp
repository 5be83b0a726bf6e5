#include "skyloc/dsp/legendre.h"

#include <gtest/gtest.h>

#include <boost/math/special_functions/spherical_harmonic.hpp>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

namespace skyloc::dsp {
namespace {

constexpr int kBands = 256;

std::vector<double> Triangle(int bands, double theta) {
  std::vector<double> p(LegendreTriangleSize(bands));
  EXPECT_TRUE(NormalisedLegendre(bands, std::cos(theta), std::sin(theta), p));
  return p;
}

// Reference: Boost.Math's Y_l^m(θ, 0) = P̄_lm(cos θ) (Condon–Shortley phase included), in
// long double. Tolerance relative to the natural scale sqrt((2l+1)/4π).
TEST(Legendre, MatchesBoostLongDoubleAtL256) {
  if (std::numeric_limits<long double>::digits <= std::numeric_limits<double>::digits) {
    GTEST_SKIP() << "Boost's reference is only more precise than this code with a long double "
                    "wider than double; on this target (e.g. armhf) they are the same type";
  }
  for (double theta : {0.05, 0.7, 1.3, 1.5707, 2.4}) {
    const std::vector<double> p = Triangle(kBands, theta);
    double worst = 0;
    for (int l = 0; l < kBands; l += 5) {
      for (int m = 0; m <= l; m += (m < 4 ? 1 : 9)) {
        const long double ref = boost::math::spherical_harmonic_r<long double>(
            static_cast<unsigned>(l), m, static_cast<long double>(theta), 0.0L);
        const double scale = std::sqrt((2.0 * l + 1) / (4 * std::numbers::pi));
        worst =
            std::max(worst, std::fabs(p[LegendreIndex(l, m)] - static_cast<double>(ref)) / scale);
      }
    }
    EXPECT_LT(worst, 1e-12) << "theta=" << theta;
  }
}

// Second reference: std::sph_legendre (libstdc++), for every (l, m) with l ≤ 120.
TEST(Legendre, MatchesStdSphLegendreUpToL120) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> angle(0.0, std::numbers::pi);
  for (int trial = 0; trial < 4; ++trial) {
    const double theta = angle(rng);
    const std::vector<double> p = Triangle(121, theta);
    for (unsigned l = 0; l <= 120; ++l)
      for (unsigned m = 0; m <= l; ++m)
        ASSERT_NEAR(p[LegendreIndex(static_cast<int>(l), static_cast<int>(m))],
                    std::sph_legendre(l, m, theta), 1e-11)
            << "l=" << l << " m=" << m << " theta=" << theta;
  }
}

// The addition theorem: P̄_l0² + 2 Σ_{m>0} P̄_lm² = (2l+1)/(4π) for every θ, including next to
// the poles where the sectoral seeds underflow without scaling.
TEST(Legendre, SumRuleHoldsAtL256EvenNearThePoles) {
  for (double theta : {1e-6, 1e-3, 0.02, 0.9, std::numbers::pi / 2, 2.9, std::numbers::pi - 1e-4}) {
    const std::vector<double> p = Triangle(kBands, theta);
    for (int l = 0; l < kBands; ++l) {
      long double sum = 0;
      for (int m = 0; m <= l; ++m) {
        const long double v = p[LegendreIndex(l, m)];
        sum += (m == 0 ? 1 : 2) * v * v;
      }
      const double expected = (2.0 * l + 1) / (4 * std::numbers::pi);
      // 1e-11: next to a pole cos θ's own rounding (ε relative) moves P̄_l0 by ~l²·ε.
      ASSERT_NEAR(static_cast<double>(sum) / expected, 1.0, 1e-11)
          << "l=" << l << " theta=" << theta;
    }
  }
}

TEST(Legendre, KnownLowOrderValues) {
  const double theta = 0.6;
  const double x = std::cos(theta), s = std::sin(theta);
  const std::vector<double> p = Triangle(3, theta);
  const double k = 1 / std::sqrt(4 * std::numbers::pi);
  EXPECT_NEAR(p[LegendreIndex(0, 0)], k, 1e-15);
  EXPECT_NEAR(p[LegendreIndex(1, 0)], k * std::sqrt(3.0) * x, 1e-15);
  EXPECT_NEAR(p[LegendreIndex(1, 1)], -k * std::sqrt(1.5) * s, 1e-15);  // Condon–Shortley
  EXPECT_NEAR(p[LegendreIndex(2, 2)], k * std::sqrt(15.0 / 8.0) * s * s, 1e-15);
}

TEST(Legendre, RejectsBadArguments) {
  std::vector<double> p(5);
  EXPECT_FALSE(NormalisedLegendre(3, 0.5, std::sqrt(0.75), p));  // needs 6
  EXPECT_FALSE(NormalisedLegendre(0, 0.5, std::sqrt(0.75), p));
}

}  // namespace
}  // namespace skyloc::dsp
