#include "skyloc/dsp/ring_fft.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "skyloc/platform/alloc_counter.h"

namespace skyloc::dsp {
namespace {

// Reference: the DFT sums evaluated directly in double.
TEST(RingFft, MatchesDirectDftForManySizesAndRingCounts) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> value(-1.0f, 1.0f);
  for (const int n : {4, 8, 16, 64, 256, 1024}) {
    // cos/sin(2π·q/n) for q = jk mod n, exact in double.
    std::vector<double> cos_table(static_cast<std::size_t>(n)), sin_table(cos_table.size());
    for (int q = 0; q < n; ++q) {
      cos_table[static_cast<std::size_t>(q)] = std::cos(2 * std::numbers::pi * q / n);
      sin_table[static_cast<std::size_t>(q)] = std::sin(2 * std::numbers::pi * q / n);
    }
    for (const int rings : {1, 3, 8, 13, 60}) {
      if (n * rings > 64 * 256)
        continue;  // the direct reference is O(rings·n²)
      std::vector<float> x(static_cast<std::size_t>(rings * n)),
          scale(static_cast<std::size_t>(rings));
      for (float& v : x)
        v = value(rng);
      for (float& s : scale)
        s = 0.5f + value(rng);
      RingFft fft;
      ASSERT_TRUE(fft.Init(rings, n, scale));
      ASSERT_EQ(fft.bins(), static_cast<std::size_t>(n / 2 + 1));
      std::vector<float> c(fft.bins() * static_cast<std::size_t>(rings)), s(c.size());
      ASSERT_TRUE(fft.Forward(x, c, s));
      double worst = 0;
      for (int r = 0; r < rings; ++r) {
        for (int k = 0; k <= n / 2; ++k) {
          double rc = 0, rs = 0;
          for (int j = 0; j < n; ++j) {
            const auto q = static_cast<std::size_t>((j * k) % n);
            const double v = x[static_cast<std::size_t>(r * n + j)];
            rc += v * cos_table[q];
            rs += v * sin_table[q];
          }
          const auto at = static_cast<std::size_t>(k * rings + r);
          const double sc = scale[static_cast<std::size_t>(r)];
          worst = std::max({worst, std::fabs(static_cast<double>(c[at]) - sc * rc),
                            std::fabs(static_cast<double>(s[at]) - sc * rs)});
        }
      }
      // float arithmetic, sums of n terms of size ≤ 1: error grows like sqrt(n)·log n·ε.
      EXPECT_LT(worst, 2e-6 * std::sqrt(n) * std::log2(n)) << "n=" << n << " rings=" << rings;
    }
  }
}

TEST(RingFft, RejectsBadArgumentsAndAllocatesNothingPerCall) {
  RingFft fft;
  EXPECT_FALSE(fft.Init(4, 100));  // not a power of two
  EXPECT_FALSE(fft.Init(0, 64));
  EXPECT_FALSE(fft.Init(4, 2));
  const std::vector<float> wrong_scale(3, 1.0f);
  EXPECT_FALSE(fft.Init(4, 64, wrong_scale));
  ASSERT_TRUE(fft.Init(60, 256));
  std::vector<float> x(60 * 256, 1.0f), c(129 * 60), s(129 * 60);
  EXPECT_FALSE(fft.Forward(std::span(x).first(100), c, s));
  ASSERT_TRUE(AllocationCounterActive());
  AllocationScope scope;
  ASSERT_TRUE(fft.Forward(x, c, s));
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_FLOAT_EQ(c[0], 256.0f);  // DC of a constant ring
  EXPECT_NEAR(c[60], 0.0f, 1e-4f);
}

}  // namespace
}  // namespace skyloc::dsp
