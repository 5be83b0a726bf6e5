#include "skyloc/dsp/sh_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace skyloc::dsp {
namespace {

TEST(GaussLegendre, FivePointRuleMatchesTabulatedValues) {
  // Abramowitz & Stegun table 25.4, n = 5.
  std::vector<double> x(5), w(5);
  ASSERT_TRUE(GaussLegendreNodes(5, x, w));
  EXPECT_NEAR(x[0], 0.906179845938664, 1e-15);
  EXPECT_NEAR(x[1], 0.538469310105683, 1e-15);
  EXPECT_EQ(x[2], 0.0);
  EXPECT_NEAR(x[3], -0.538469310105683, 1e-15);
  EXPECT_NEAR(w[0], 0.236926885056189, 1e-15);
  EXPECT_NEAR(w[1], 0.478628670499366, 1e-15);
  EXPECT_NEAR(w[2], 0.568888888888889, 1e-15);
}

TEST(GaussLegendre, IntegratesPolynomialsUpToDegree2nMinus1Exactly) {
  for (int n : {1, 2, 7, 40, 120, 240}) {
    std::vector<double> x(static_cast<std::size_t>(n)), w(static_cast<std::size_t>(n));
    ASSERT_TRUE(GaussLegendreNodes(n, x, w));
    // Legendre polynomials are a well-conditioned test basis: ∫P_k = 2δ_k0, k ≤ 2n-1.
    for (int k = 0; k <= 2 * n - 1; k += (k < 10 ? 1 : 13)) {
      long double sum = 0;
      for (std::size_t i = 0; i < x.size(); ++i) {
        long double p_prev = 1, p = x[i];
        if (k == 0)
          p = 1;
        for (int j = 2; j <= k; ++j) {
          const long double next = ((2.0L * j - 1) * x[i] * p - (j - 1.0L) * p_prev) / j;
          p_prev = p;
          p = next;
        }
        sum += w[i] * p;
      }
      EXPECT_NEAR(static_cast<double>(sum), k == 0 ? 2.0 : 0.0, 2e-13) << "n=" << n << " k=" << k;
    }
    for (std::size_t i = 1; i < x.size(); ++i)
      EXPECT_LT(x[i], x[i - 1]) << "nodes must descend";
  }
}

TEST(GaussLegendre, RejectsShortSpans) {
  std::vector<double> x(3), w(3);
  EXPECT_FALSE(GaussLegendreNodes(4, x, w));
  EXPECT_FALSE(GaussLegendreNodes(0, x, w));
}

TEST(ShGrid, UpperHemisphereHalvesTheFullRule) {
  ShGrid upper, full;
  ASSERT_EQ(upper.Init({.rings = 30, .longitudes = 64, .coverage = ShCoverage::kUpperHemisphere}),
            ShError::kOk);
  ASSERT_EQ(full.Init({.rings = 60, .longitudes = 64, .coverage = ShCoverage::kFullSphere}),
            ShError::kOk);
  double upper_area = 0, full_area = 0;
  for (int i = 0; i < upper.ring_count(); ++i) {
    const ShRing& r = upper.ring(i);
    EXPECT_GT(r.cos_theta, 0.0);
    EXPECT_DOUBLE_EQ(r.cos_theta, full.ring(i).cos_theta);
    EXPECT_NEAR(r.cos_theta * r.cos_theta + r.sin_theta * r.sin_theta, 1.0, 1e-15);
    EXPECT_NEAR(std::cos(r.theta), r.cos_theta, 1e-15);
    upper_area += r.weight * upper.longitudes();
  }
  for (const ShRing& r : full.rings())
    full_area += r.weight * full.longitudes();
  EXPECT_NEAR(upper_area, 2 * std::numbers::pi, 1e-12);
  EXPECT_NEAR(full_area, 4 * std::numbers::pi, 1e-12);
  EXPECT_EQ(upper.sample_count(), 30u * 64u);
}

TEST(ShGrid, DirectionsAreRingMajorUnitVectors) {
  ShGrid grid;
  ASSERT_EQ(grid.Init({.rings = 5, .longitudes = 8}), ShError::kOk);
  const ShDirection d = grid.direction(2 * 8 + 3);
  EXPECT_DOUBLE_EQ(d.theta, grid.ring(2).theta);
  EXPECT_DOUBLE_EQ(d.phi, 3 * 2 * std::numbers::pi / 8);
  EXPECT_NEAR(d.x * d.x + d.y * d.y + d.z * d.z, 1.0, 1e-15);
  EXPECT_NEAR(d.z, grid.ring(2).cos_theta, 1e-15);
  EXPECT_NEAR(std::atan2(d.y, d.x), 3 * std::numbers::pi / 4, 1e-14);
}

TEST(ShGrid, DefaultGridResolvesItsBandsAndThePaperGridDoesNot) {
  const ShGridConfig def = DefaultShGridConfig(120);
  EXPECT_EQ(def.rings, 60);
  EXPECT_EQ(def.longitudes, 256);
  EXPECT_TRUE(ShGridResolvesBands(def, 120));
  EXPECT_FALSE(ShGridResolvesBands(def, 121));
  for (int bands : {1, 2, 3, 17, 64, 255, 256, 512})
    EXPECT_TRUE(ShGridResolvesBands(DefaultShGridConfig(bands), bands)) << bands;

  const ShGridConfig paper = PaperShGridConfig();
  EXPECT_EQ(paper.rings * paper.longitudes, 2048);
  EXPECT_TRUE(ShGridResolvesBands(paper, 32));
  EXPECT_FALSE(ShGridResolvesBands(paper, 33));
  EXPECT_FALSE(ShGridResolvesBands(paper, 120));
}

TEST(ShGrid, InvalidConfigsAreErrorsWithMessages) {
  ShGrid grid;
  EXPECT_EQ(grid.Init({.rings = 0, .longitudes = 64}), ShError::kRingsOutOfRange);
  EXPECT_FALSE(grid.initialised());
  EXPECT_EQ(grid.Init({.rings = kMaxShRings + 1, .longitudes = 64}), ShError::kRingsOutOfRange);
  EXPECT_EQ(grid.Init({.rings = 8, .longitudes = 3}), ShError::kLongitudesOutOfRange);
  EXPECT_EQ(grid.Init({.rings = 8, .longitudes = kMaxShLongitudes + 1}),
            ShError::kLongitudesOutOfRange);
  EXPECT_EQ(grid.Init({.rings = 8, .longitudes = 100}), ShError::kLongitudesNotPowerOfTwo);
  EXPECT_NE(std::string(ShErrorMessage(ShError::kRingsOutOfRange)).find("ring"), std::string::npos);
}

}  // namespace
}  // namespace skyloc::dsp
