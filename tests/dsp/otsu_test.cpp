#include "skyloc/dsp/otsu.h"

#include <gtest/gtest.h>

#include <random>

namespace skyloc::dsp {
namespace {

// Independent reference: for every threshold, compute both class means and weights from
// scratch in long double and keep the first maximum of w0*w1*(mu0-mu1)^2.
int BruteForceOtsu(const Histogram256& h) {
  long double best = -1;
  int best_t = 0;
  for (int t = 0; t < 255; ++t) {
    long double n0 = 0, n1 = 0, s0 = 0, s1 = 0;
    for (int v = 0; v < 256; ++v) {
      const long double c = h[static_cast<std::size_t>(v)];
      if (v <= t) {
        n0 += c;
        s0 += c * v;
      } else {
        n1 += c;
        s1 += c * v;
      }
    }
    if (n0 == 0 || n1 == 0)
      continue;
    const long double n = n0 + n1;
    const long double between = (n0 / n) * (n1 / n) * (s0 / n0 - s1 / n1) * (s0 / n0 - s1 / n1);
    // A relative tolerance keeps ties decided the same way as the double implementation.
    if (between > best * (1 + 1e-12L)) {
      best = between;
      best_t = t;
    }
  }
  return best_t;
}

TEST(Otsu, MatchesBruteForceOnRandomHistograms) {
  std::mt19937 rng(42);
  for (int trial = 0; trial < 300; ++trial) {
    Histogram256 h{};
    const int mode = trial % 3;
    for (int v = 0; v < 256; ++v) {
      auto c = static_cast<std::uint32_t>(rng() % 1000);
      if (mode == 1 && (v % 17) != 0)
        c = 0;  // sparse
      if (mode == 2)
        c = (v < 80 || v > 180) ? c * 20 : c;  // bimodal
      h[static_cast<std::size_t>(v)] = c;
    }
    const OtsuResult r = OtsuThreshold(h);
    const int expected = BruteForceOtsu(h);
    // Equal, or an exactly tied neighbour in a sparse histogram (empty bins between
    // populated ones give the same split).
    if (r.threshold != expected) {
      std::uint64_t between_bins = 0;
      for (int v = std::min(r.threshold, expected) + 1; v <= std::max(r.threshold, expected); ++v)
        between_bins += h[static_cast<std::size_t>(v)];
      EXPECT_EQ(between_bins, 0u) << "trial " << trial << ": " << r.threshold << " vs " << expected;
    }
  }
}

TEST(Otsu, TwoSpikesSplitBetweenThem) {
  Histogram256 h{};
  h[30] = 500;
  h[200] = 700;
  const OtsuResult r = OtsuThreshold(h);
  EXPECT_GE(r.threshold, 30);
  EXPECT_LT(r.threshold, 200);
  EXPECT_NEAR(r.separability, 1.0, 1e-12);  // two spikes: all variance is between classes
}

TEST(Otsu, DegenerateHistograms) {
  Histogram256 empty{};
  EXPECT_EQ(OtsuThreshold(empty).threshold, 0);
  EXPECT_EQ(OtsuThreshold(empty).separability, 0.0);
  Histogram256 flat{};
  flat[128] = 1000;
  EXPECT_EQ(OtsuThreshold(flat).separability, 0.0);
}

TEST(Otsu, BimodalNoisyImageSegmentsAbove99Percent) {
  // Sky ~ N(200, 15), ground ~ N(50, 15): the optimal split misclassifies ~0.0000003 %.
  std::mt19937 rng(7);
  std::normal_distribution<double> sky(200, 15), ground(50, 15);
  Histogram256 h{};
  std::vector<std::pair<std::uint8_t, bool>> pixels;
  for (int i = 0; i < 50000; ++i) {
    const bool is_sky = (i % 3) == 0;
    const double v = std::clamp(is_sky ? sky(rng) : ground(rng), 0.0, 255.0);
    const auto p = static_cast<std::uint8_t>(v);
    pixels.emplace_back(p, is_sky);
    ++h[p];
  }
  const int t = OtsuThreshold(h).threshold;
  std::size_t correct = 0;
  for (auto [v, is_sky] : pixels)
    correct += ((v > t) == is_sky) ? 1 : 0;
  EXPECT_GT(static_cast<double>(correct) / static_cast<double>(pixels.size()), 0.99);
}

}  // namespace
}  // namespace skyloc::dsp
