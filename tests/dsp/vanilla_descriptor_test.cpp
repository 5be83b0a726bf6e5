#include "skyloc/dsp/vanilla_descriptor.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace skyloc::dsp {
namespace {

ImageView Grey(const std::vector<std::uint8_t>& px, int w, int h) {
  return ImageView{px.data(), w, h, static_cast<std::size_t>(w), PixelFormat::kGrey8};
}

TEST(VanillaDescriptor, IntegerShrinkIsBlockMeanThenPatchZScores) {
  // 128x64 -> 64x32: every output pixel is the mean of a 2x2 block. Reference computed
  // here independently (block means, then two-pass z-scores per 8x8 patch).
  std::mt19937 rng(4);
  std::vector<std::uint8_t> px(128 * 64);
  for (auto& p : px)
    p = static_cast<std::uint8_t>(rng() % 256);
  std::vector<float> out(kVanillaDescriptorSize);
  ASSERT_EQ(VanillaDescriptor(Grey(px, 128, 64), out), VanillaError::kOk);
  std::vector<double> small(64 * 32);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 64; ++x) {
      auto at = [&](int xx, int yy) {
        return static_cast<double>(px[static_cast<std::size_t>(yy * 128 + xx)]);
      };
      small[static_cast<std::size_t>(y * 64 + x)] =
          (at(2 * x, 2 * y) + at(2 * x + 1, 2 * y) + at(2 * x, 2 * y + 1) +
           at(2 * x + 1, 2 * y + 1)) /
          4;
    }
  for (int py = 0; py < 32; py += 8)
    for (int px0 = 0; px0 < 64; px0 += 8) {
      double mean = 0;
      for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x)
          mean += small[static_cast<std::size_t>((py + y) * 64 + px0 + x)];
      mean /= 64;
      double var = 0;
      for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
          const double d = small[static_cast<std::size_t>((py + y) * 64 + px0 + x)] - mean;
          var += d * d;
        }
      const double sd = std::sqrt(var / 63);
      for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
          const std::size_t i = static_cast<std::size_t>((py + y) * 64 + px0 + x);
          EXPECT_NEAR(out[i], (small[i] - mean) / sd, 1e-4);
        }
    }
}

TEST(VanillaDescriptor, AreaResizeKeepsTheMeanForFractionalScales) {
  // 100x45 -> 64x32 (scales 1.5625 and 1.40625) and 40x20 -> 64x32 (enlarging).
  for (const auto& [w, h] : {std::pair{100, 45}, std::pair{40, 20}}) {
    std::mt19937 rng(static_cast<unsigned>(w));
    std::vector<std::uint8_t> px(static_cast<std::size_t>(w * h));
    double mean = 0;
    for (auto& p : px) {
      p = static_cast<std::uint8_t>(rng() % 256);
      mean += p;
    }
    mean /= static_cast<double>(px.size());
    std::vector<float> out(64 * 32);
    ASSERT_TRUE(AreaResizeLuminance(Grey(px, w, h), 64, 32, out));
    double out_mean = 0;
    for (float v : out) {
      out_mean += static_cast<double>(v);
      EXPECT_GE(v, 0.0f);
      EXPECT_LE(v, 255.0f);
    }
    EXPECT_NEAR(out_mean / static_cast<double>(out.size()), mean, 1e-3) << w << "x" << h;
  }
  // A constant image stays constant whatever the scale.
  std::vector<std::uint8_t> flat(77 * 33, 90);
  std::vector<float> out(64 * 32);
  ASSERT_TRUE(AreaResizeLuminance(Grey(flat, 77, 33), 64, 32, out));
  for (float v : out)
    EXPECT_NEAR(v, 90.0f, 1e-3f);
}

TEST(VanillaDescriptor, FlatPatchesGiveFiniteZeros) {
  std::vector<std::uint8_t> px(64 * 32, 200);
  // One textured patch (top-left 8x8), the rest flat.
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x)
      px[static_cast<std::size_t>(y * 64 + x)] = static_cast<std::uint8_t>(10 * (x + y));
  std::vector<float> out(kVanillaDescriptorSize);
  ASSERT_EQ(VanillaDescriptor(Grey(px, 64, 32), out), VanillaError::kOk);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 64; ++x) {
      const float v = out[static_cast<std::size_t>(y * 64 + x)];
      EXPECT_TRUE(std::isfinite(v));
      if (x >= 8 || y >= 8) {
        EXPECT_EQ(v, 0.0f);
      }
    }
  EXPECT_LT(out[0], -1.0f);  // the darkest corner of the textured patch
}

TEST(VanillaDescriptor, InvariantToPerPatchGainAndOffsetAndColourLayout) {
  std::mt19937 rng(9);
  std::vector<std::uint8_t> grey(64 * 32), brighter(64 * 32), rgb(64 * 32 * 3), bgr(64 * 32 * 3);
  for (std::size_t i = 0; i < grey.size(); ++i) {
    grey[i] = static_cast<std::uint8_t>(rng() % 100);
    brighter[i] = static_cast<std::uint8_t>(2 * grey[i] + 30);  // exposure change
    rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = grey[i];
    bgr[3 * i] = bgr[3 * i + 1] = bgr[3 * i + 2] = grey[i];
  }
  std::vector<float> a(kVanillaDescriptorSize), b(kVanillaDescriptorSize),
      c(kVanillaDescriptorSize), d(kVanillaDescriptorSize);
  ASSERT_EQ(VanillaDescriptor(Grey(grey, 64, 32), a), VanillaError::kOk);
  ASSERT_EQ(VanillaDescriptor(Grey(brighter, 64, 32), b), VanillaError::kOk);
  ASSERT_EQ(VanillaDescriptor(ImageView{rgb.data(), 64, 32, 192, PixelFormat::kRgb24}, c),
            VanillaError::kOk);
  ASSERT_EQ(VanillaDescriptor(ImageView{bgr.data(), 64, 32, 192, PixelFormat::kBgr24}, d),
            VanillaError::kOk);
  EXPECT_LT(SumAbsoluteDifference(a, b), 1e-2f);
  EXPECT_LT(SumAbsoluteDifference(a, c), 1e-2f);
  EXPECT_LT(SumAbsoluteDifference(a, d), 1e-2f);
  std::vector<std::uint8_t> other(64 * 32);
  for (auto& p : other)
    p = static_cast<std::uint8_t>(rng() % 100);
  std::vector<float> e(kVanillaDescriptorSize);
  ASSERT_EQ(VanillaDescriptor(Grey(other, 64, 32), e), VanillaError::kOk);
  EXPECT_GT(SumAbsoluteDifference(a, e), 500.0f);  // ~1.1 per element for unrelated images
}

TEST(VanillaDescriptor, RejectsBadInput) {
  std::vector<float> out(kVanillaDescriptorSize), small(10);
  std::vector<std::uint8_t> px(16);
  EXPECT_EQ(VanillaDescriptor(ImageView{}, out), VanillaError::kEmptyImage);
  EXPECT_EQ(VanillaDescriptor(Grey(px, 4, 4), small), VanillaError::kBadOutputSize);
  EXPECT_EQ(VanillaDescriptor(ImageView{px.data(), 4, 4, 2, PixelFormat::kGrey8}, out),
            VanillaError::kEmptyImage);
  EXPECT_STREQ(VanillaErrorMessage(VanillaError::kEmptyImage),
               "image is empty or its stride is shorter than a row");
  const float x[3] = {1, 2, 3}, y[3] = {2, 0, 3};
  EXPECT_FLOAT_EQ(SumAbsoluteDifference(x, y), 3.0f);
}

}  // namespace
}  // namespace skyloc::dsp
