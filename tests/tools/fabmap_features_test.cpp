#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "skyloc/dsp/image.h"
#include "tools/features.h"

namespace skyloc::tools {
namespace {

// A textured test card: dark and bright discs of several sizes on a gradient.
std::vector<std::uint8_t> TestCard(int w, int h) {
  std::vector<std::uint8_t> px(static_cast<std::size_t>(w * h));
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  struct Disc {
    double x, y, r;
    int v;
  };
  std::vector<Disc> discs;
  for (int k = 0; k < 40; ++k)
    discs.push_back({u(rng) * w, u(rng) * h, 4 + u(rng) * 20, u(rng) < 0.5 ? 20 : 235});
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      int v = 80 + (x * 60) / w;
      for (const Disc& d : discs)
        if ((x - d.x) * (x - d.x) + (y - d.y) * (y - d.y) < d.r * d.r)
          v = d.v;
      px[static_cast<std::size_t>(y * w + x)] = static_cast<std::uint8_t>(v);
    }
  }
  return px;
}

TEST(FabmapFeatures, SiftFindsFeaturesAndGreyEqualsRgb) {
  const int w = 640, h = 360;
  const std::vector<std::uint8_t> grey = TestCard(w, h);
  std::vector<std::uint8_t> rgb;
  for (const std::uint8_t v : grey)
    rgb.insert(rgb.end(), {v, v, v});
  FeatureSettings s;
  s.max_features = 100;
  std::vector<float> a, b;
  ASSERT_TRUE(
      ExtractSift({grey.data(), w, h, static_cast<std::size_t>(w), dsp::PixelFormat::kGrey8}, s, &a)
          .ok());
  ASSERT_TRUE(
      ExtractSift({rgb.data(), w, h, static_cast<std::size_t>(3 * w), dsp::PixelFormat::kRgb24}, s,
                  &b)
          .ok());
  ASSERT_EQ(a.size() % kSiftDim, 0u);
  const std::size_t n = a.size() / kSiftDim;
  EXPECT_GE(n, 20u);
  EXPECT_LE(n, 100u);
  EXPECT_EQ(a, b);
  std::vector<float> none;
  EXPECT_FALSE(ExtractSift({}, s, &none).ok());
}

TEST(FabmapFeatures, KMeansFindsSeparatedClustersAndQuantiseIsNearestCentre) {
  // Four well-separated clusters in 128 dimensions.
  constexpr int kDim = kSiftDim;
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  std::vector<std::vector<float>> truth(4, std::vector<float>(kDim, 0.0f));
  for (int c = 0; c < 4; ++c)
    for (int d = 0; d < 32; ++d)
      truth[static_cast<std::size_t>(c)][static_cast<std::size_t>(c * 32 + d)] = 100.0f;
  std::vector<float> data;
  for (int i = 0; i < 400; ++i)
    for (int d = 0; d < kDim; ++d)
      data.push_back(truth[static_cast<std::size_t>(i % 4)][static_cast<std::size_t>(d)] +
                     noise(rng));
  std::vector<float> centres;
  ASSERT_TRUE(ClusterWords(data, kDim, 4, 11, &centres).ok());
  ASSERT_EQ(centres.size(), 4u * kDim);
  // Every true centre has a found centre within noise of it.
  for (const std::vector<float>& t : truth) {
    double best = 1e30;
    for (int c = 0; c < 4; ++c) {
      double d2 = 0;
      for (int d = 0; d < kDim; ++d) {
        const double e =
            centres[static_cast<std::size_t>(c * kDim + d)] - t[static_cast<std::size_t>(d)];
        d2 += e * e;
      }
      best = std::min(best, d2);
    }
    EXPECT_LT(std::sqrt(best), 3.0);
  }
  // Quantise against a brute-force nearest centre, on fresh points.
  for (int i = 0; i < 50; ++i) {
    std::vector<float> p(kDim);
    for (float& x : p)
      x = noise(rng) * 60.0f + 30.0f;
    std::size_t nearest = 0;
    double best = 1e30;
    for (std::size_t c = 0; c < 4; ++c) {
      double d2 = 0;
      for (std::size_t d = 0; d < kDim; ++d) {
        const double e = p[d] - centres[c * kDim + d];
        d2 += e * e;
      }
      if (d2 < best) {
        best = d2;
        nearest = c;
      }
    }
    WordList w;
    ASSERT_TRUE(Quantise(p, centres, kDim, &w).ok());
    ASSERT_EQ(w.size(), 1u);
    EXPECT_EQ(w[0], nearest);
  }
  EXPECT_FALSE(ClusterWords(std::vector<float>(kDim * 3, 0.0f), kDim, 4, 1, &centres).ok());
}

}  // namespace
}  // namespace skyloc::tools
