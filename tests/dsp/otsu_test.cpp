#include "skyloc/dsp/otsu.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
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

namespace skyloc::dsp {
namespace {

// The histogram of `pixels` draws: with probability `sky` a pixel is N(sky_level, sigma),
// else N(ground_level, sigma), rounded and clipped to 0..255 as a sensor does.
Histogram256 TwoLevels(double ground_level, double sky_level, double sky, double sigma,
                       std::uint32_t seed, int pixels = 40000) {
  std::mt19937 rng(seed);
  std::bernoulli_distribution is_sky(sky);
  std::normal_distribution<double> noise(0.0, sigma);
  Histogram256 h{};
  for (int i = 0; i < pixels; ++i) {
    const double level = is_sky(rng) ? sky_level : ground_level;
    const long v = std::lround(level + (sigma > 0 ? noise(rng) : 0.0));
    ++h[static_cast<std::size_t>(v < 0 ? 0 : v > 255 ? 255 : v)];
  }
  return h;
}

// Otsu splits any histogram; only two classes of pixels are sky and ground. One level and
// its noise anywhere in the range (clipped at black or white too, with up to the 10
// levels of noise otsu.h allows for), or an even spread of levels (shading), is one class.
TEST(Otsu, OneLevelAndItsNoiseIsNotSkyAndGround) {
  for (const double level : {0.0, 1.0, 3.0, 60.0, 128.0, 250.0, 255.0}) {
    for (const double sigma : {0.0, 0.3, 0.5, 1.0, 2.0, 3.0, 5.0, 8.0}) {
      const Histogram256 h = TwoLevels(level, level, 0.0, sigma, 5);
      EXPECT_FALSE(SeparatesSkyFromGround(OtsuThreshold(h))) << level << " +- " << sigma;
    }
  }
  // Unclipped, any noise at all.
  for (const double sigma : {20.0, 40.0}) {
    const Histogram256 h = TwoLevels(128, 128, 0.0, sigma, 5);
    EXPECT_FALSE(SeparatesSkyFromGround(OtsuThreshold(h))) << "128 +- " << sigma;
  }
  for (const int width : {2, 10, 40, 120, 256}) {
    Histogram256 even{};
    for (int v = 0; v < width; ++v)
      even[static_cast<std::size_t>(v)] = 100;
    EXPECT_FALSE(SeparatesSkyFromGround(OtsuThreshold(even))) << "0.." << width - 1;
  }
  EXPECT_FALSE(SeparatesSkyFromGround(OtsuThreshold(Histogram256{})));
}

// Two levels whose noise leaves them apart (6 sigma, at least 16 levels) are sky and
// ground, whatever the share of sky between a tenth and nine tenths.
TEST(Otsu, TwoLevelsWellApartAreSkyAndGround) {
  for (const double sky : {0.1, 0.3, 0.5, 0.7, 0.9}) {
    for (const double sigma : {0.0, 1.0, 2.0, 5.0, 15.0}) {
      const double ground_level = 40;
      const double sky_level = ground_level + std::max(16.0, 6.0 * sigma);
      const Histogram256 h = TwoLevels(ground_level, sky_level, sky, sigma, 6);
      const OtsuResult otsu = OtsuThreshold(h);
      EXPECT_TRUE(SeparatesSkyFromGround(otsu)) << sky << ", sigma " << sigma;
    }
  }
  // The class means are those of the two spikes.
  Histogram256 spikes{};
  spikes[30] = 500;
  spikes[200] = 700;
  const OtsuResult r = OtsuThreshold(spikes);
  EXPECT_DOUBLE_EQ(r.low_mean, 30.0);
  EXPECT_DOUBLE_EQ(r.high_mean, 200.0);
  EXPECT_NEAR(r.within_sigma, std::sqrt(1.0 / 12.0), 1e-9);
}

}  // namespace
}  // namespace skyloc::dsp
