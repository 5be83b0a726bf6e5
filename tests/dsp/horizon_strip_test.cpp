#include "skyloc/dsp/horizon_strip.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "skyloc/platform/alloc_counter.h"

namespace skyloc::dsp {
namespace {

Lens MakeLens(LensModel model, int w, int h, double fov_deg) {
  LensParams p;
  p.model = model;
  p.width = w;
  p.height = h;
  p.fov_deg = fov_deg;
  Lens lens;
  EXPECT_EQ(lens.Init(p), LensError::kOk);
  return lens;
}

std::uint8_t Pattern(int x, int y) {
  return static_cast<std::uint8_t>(1 + (3 * x + 5 * y) % 250);
}

// Equirectangular maps azimuth and elevation to pixels by a formula (lens.h), so every
// strip entry can be predicted from the pattern directly: the mean over the band rows of
// the nearest pixel. The sizes keep most taps off pixel boundaries; columns whose taps
// fall on a boundary (a rounding tie) are skipped.
TEST(HorizonStripTest, EquirectangularStripIsTheBandMeanOfThePattern) {
  const int w = 700, h = 360;
  const Lens lens = MakeLens(LensModel::kEquirectangular, w, h, 360.0);
  HorizonStripOptions options;
  options.n_azimuth = 360;
  options.band_rows = 8;
  options.elevation_min_deg = 2.3;
  options.elevation_max_deg = 18.3;
  HorizonStrip strip;
  ASSERT_EQ(strip.Init(lens, options), HorizonStripError::kOk);
  EXPECT_DOUBLE_EQ(strip.visible_fraction(), 1.0);
  EXPECT_EQ(strip.empty_columns(), 0);

  std::vector<std::uint8_t> grey(static_cast<std::size_t>(w * h));
  std::vector<std::uint8_t> rgb(grey.size() * 3), bgr(grey.size() * 3), yuyv(grey.size() * 2);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const auto i = static_cast<std::size_t>(y * w + x);
      const std::uint8_t g = Pattern(x, y);
      grey[i] = g;
      // Channels whose integer mean is g, in different orders.
      rgb[3 * i] = static_cast<std::uint8_t>(g + 1);
      rgb[3 * i + 1] = static_cast<std::uint8_t>(g - 1);
      rgb[3 * i + 2] = g;
      bgr[3 * i] = g;
      bgr[3 * i + 1] = static_cast<std::uint8_t>(g - 1);
      bgr[3 * i + 2] = static_cast<std::uint8_t>(g + 1);
      yuyv[2 * i] = g;
      yuyv[2 * i + 1] = static_cast<std::uint8_t>(255 - g);  // chroma must be ignored
    }
  }
  std::vector<float> expected(360);
  std::vector<bool> tie(360, false);
  for (int j = 0; j < 360; ++j) {
    const double phi = 2.0 * std::numbers::pi * j / 360.0;
    const double xf = phi * w / (2 * std::numbers::pi) - 0.5;
    tie[static_cast<std::size_t>(j)] = std::abs(xf - std::round(xf)) > 0.49;
    const int x = static_cast<int>(std::floor(xf + 0.5));
    double sum = 0.0;
    for (int r = 0; r < options.band_rows; ++r) {
      const double elevation = 2.3 + (r + 0.5) / options.band_rows * 16.0;
      const double theta = (90.0 - elevation) * std::numbers::pi / 180.0;
      const double yf = theta * h / std::numbers::pi - 0.5;
      ASSERT_LT(std::abs(yf - std::round(yf)), 0.45);
      sum += Pattern(x, static_cast<int>(std::floor(yf + 0.5)));
    }
    expected[static_cast<std::size_t>(j)] = static_cast<float>(sum / options.band_rows);
  }
  ASSERT_LE(std::count(tie.begin(), tie.end(), true), 25);
  const struct {
    const std::vector<std::uint8_t>* data;
    PixelFormat format;
    int bytes;
  } cases[] = {{&grey, PixelFormat::kGrey8, 1},
               {&rgb, PixelFormat::kRgb24, 3},
               {&bgr, PixelFormat::kBgr24, 3},
               {&yuyv, PixelFormat::kYuyv, 2}};
  std::vector<float> out(360);
  for (const auto& c : cases) {
    const ImageView image{c.data->data(), w, h, static_cast<std::size_t>(w * c.bytes), c.format};
    ASSERT_EQ(strip.Extract(image, out), HorizonStripError::kOk);
    for (std::size_t j = 0; j < out.size(); ++j) {
      if (tie[j])
        continue;
      ASSERT_NEAR(out[j], expected[j], 1e-4) << PixelFormatName(c.format) << " column " << j;
    }
  }
}

TEST(HorizonStripTest, FisheyeSeesTheBandOrSaysItCannot) {
  const Lens wide = MakeLens(LensModel::kEquidistant, 640, 480, 185.0);
  HorizonStrip strip;
  ASSERT_EQ(strip.Init(wide, HorizonStripOptions{}), HorizonStripError::kOk);
  EXPECT_DOUBLE_EQ(strip.visible_fraction(), 1.0);

  // A 170-degree lens cannot see 10 degrees below the horizon.
  const Lens narrow = MakeLens(LensModel::kEquidistant, 640, 480, 170.0);
  HorizonStripOptions below;
  below.elevation_min_deg = -10.0;
  below.elevation_max_deg = -6.0;
  EXPECT_EQ(strip.Init(narrow, below), HorizonStripError::kNotVisible);
  // It sees down to +5 degrees: half of a 0 .. 10 degree band.
  HorizonStripOptions straddle;
  straddle.elevation_min_deg = 0.0;
  straddle.elevation_max_deg = 10.0;
  straddle.band_rows = 10;
  ASSERT_EQ(strip.Init(narrow, straddle), HorizonStripError::kOk);
  EXPECT_NEAR(strip.visible_fraction(), 0.5, 0.05);
}

TEST(HorizonStripTest, RejectsBadOptionsFramesAndBuffers) {
  const Lens lens = MakeLens(LensModel::kEquidistant, 64, 48, 185.0);
  HorizonStrip strip;
  HorizonStripOptions o;
  o.n_azimuth = 4;
  EXPECT_EQ(strip.Init(lens, o), HorizonStripError::kBadOptions);
  o = {};
  o.band_rows = 0;
  EXPECT_EQ(strip.Init(lens, o), HorizonStripError::kBadOptions);
  o = {};
  o.elevation_min_deg = 30.0;
  o.elevation_max_deg = 10.0;
  EXPECT_EQ(strip.Init(lens, o), HorizonStripError::kBadOptions);
  o = {};
  o.elevation_max_deg = 95.0;
  EXPECT_EQ(strip.Init(lens, o), HorizonStripError::kBadOptions);
  EXPECT_NE(std::string(HorizonStripErrorMessage(HorizonStripError::kBadOptions)).find("band"),
            std::string::npos);

  ASSERT_EQ(strip.Init(lens, HorizonStripOptions{}), HorizonStripError::kOk);
  std::vector<std::uint8_t> grey(64 * 48, 100);
  std::vector<float> out(360);
  const ImageView wrong{grey.data(), 48, 64, 48, PixelFormat::kGrey8};
  EXPECT_EQ(strip.Extract(wrong, out), HorizonStripError::kSizeMismatch);
  const ImageView right{grey.data(), 64, 48, 64, PixelFormat::kGrey8};
  std::vector<float> short_out(359);
  EXPECT_EQ(strip.Extract(right, short_out), HorizonStripError::kBadOutputSize);
  ASSERT_EQ(strip.Extract(right, out), HorizonStripError::kOk);
  for (const float v : out)
    EXPECT_FLOAT_EQ(v, 100.0f);
}

TEST(HorizonStripTest, ExtractAllocatesNothing) {
  ASSERT_TRUE(AllocationCounterActive());
  const Lens lens = MakeLens(LensModel::kEquidistant, 640, 480, 185.0);
  HorizonStrip strip;
  ASSERT_EQ(strip.Init(lens, HorizonStripOptions{}), HorizonStripError::kOk);
  std::vector<std::uint8_t> rgb(640 * 480 * 3, 77);
  std::vector<float> out(360);
  const ImageView image{rgb.data(), 640, 480, 640 * 3, PixelFormat::kRgb24};
  AllocationScope scope;
  for (int i = 0; i < 3; ++i)
    ASSERT_EQ(strip.Extract(image, out), HorizonStripError::kOk);
  EXPECT_EQ(scope.allocations(), 0u);
}

// The bytes are the nearest grey level, halves away from zero, clamped to 0..255: written
// out by hand, not computed the way StripToBytes computes them.
TEST(StripToBytes, RoundsToNearestAndClamps) {
  const std::vector<float> strip = {-3.0f,  -0.4f,  0.0f,   0.49f,  0.5f,   1.5f,  2.5f,
                                    127.4f, 127.6f, 254.5f, 255.0f, 255.4f, 300.0f};
  const std::vector<std::uint8_t> expected = {0, 0, 0, 0, 1, 2, 3, 127, 128, 255, 255, 255, 255};
  std::vector<std::uint8_t> bytes(strip.size(), 77);
  ASSERT_EQ(StripToBytes(strip, bytes), HorizonStripError::kOk);
  EXPECT_EQ(bytes, expected);
}

TEST(StripToBytes, RefusesAnOutputOfAnotherLength) {
  const std::vector<float> strip(8, 10.0f);
  std::vector<std::uint8_t> bytes(7, 77);
  EXPECT_EQ(StripToBytes(strip, bytes), HorizonStripError::kBadOutputSize);
  EXPECT_EQ(bytes, std::vector<std::uint8_t>(7, 77));  // untouched
}

TEST(StripToBytes, AllocatesNothing) {
  const std::vector<float> strip(360, 100.25f);
  std::vector<std::uint8_t> bytes(strip.size());
  const AllocationScope scope;
  ASSERT_EQ(StripToBytes(strip, bytes), HorizonStripError::kOk);
  EXPECT_EQ(scope.allocations(), 0u);
}

// The 4-bit strip against a quantiser written out in doubles: the range [lo - 0.5,
// hi + 0.5] of the strip's bytes cut into 16 equal bins, each byte to the bin its value
// falls in, decoded as the bin's centre. Not the integer arithmetic PackStrip uses.
std::vector<float> ReferenceFourBits(const std::vector<std::uint8_t>& bytes) {
  const double lo = *std::min_element(bytes.begin(), bytes.end());
  const double hi = *std::max_element(bytes.begin(), bytes.end());
  const double bin = (hi - lo + 1.0) / 16.0;
  std::vector<float> out;
  for (const std::uint8_t v : bytes) {
    const double level = std::min(15.0, std::floor((v - (lo - 0.5)) / bin));
    out.push_back(static_cast<float>(lo - 0.5 + (level + 0.5) * bin));
  }
  return out;
}

TEST(PackStrip, FourBitsAreTheReferenceQuantiserOnRandomStrips) {
  std::uint32_t state = 12345;
  const auto next = [&] {
    state = state * 1664525u + 1013904223u;
    return state >> 8;
  };
  for (int trial = 0; trial < 2000; ++trial) {
    const std::size_t columns = 8 + next() % 400;  // odd and even lengths
    const unsigned lo = next() % 256;
    const unsigned range = next() % (256 - lo);
    std::vector<std::uint8_t> bytes(columns);
    for (std::uint8_t& b : bytes)
      b = static_cast<std::uint8_t>(lo + next() % (range + 1));
    std::vector<std::uint8_t> packed(PackedStripBytes(columns));
    ASSERT_EQ(PackStrip(bytes, packed), HorizonStripError::kOk);
    std::vector<float> decoded(columns);
    ASSERT_EQ(UnpackStrip(packed, decoded), HorizonStripError::kOk);
    const std::vector<float> reference = ReferenceFourBits(bytes);
    const float width = static_cast<float>(packed[1]) + 1.0f;
    for (std::size_t j = 0; j < columns; ++j) {
      ASSERT_EQ(decoded[j], reference[j]) << "trial " << trial << " column " << j;
      ASSERT_LE(std::fabs(decoded[j] - static_cast<float>(bytes[j])), width / 32.0f);
    }
    if (columns % 2 == 1) {
      EXPECT_EQ(packed.back() >> 4, 0);  // the unused nibble
    }
  }
}

TEST(PackStrip, SixteenGreyLevelsComeBackExactly) {
  std::vector<std::uint8_t> bytes;
  for (int j = 0; j < 160; ++j)
    bytes.push_back(static_cast<std::uint8_t>(100 + (j * 7) % 16));
  std::vector<std::uint8_t> packed(PackedStripBytes(bytes.size()));
  ASSERT_EQ(PackStrip(bytes, packed), HorizonStripError::kOk);
  EXPECT_EQ(packed[0], 100);
  EXPECT_EQ(packed[1], 15);
  EXPECT_EQ(packed.size(), 2u + 80u);
  std::vector<float> decoded(bytes.size());
  ASSERT_EQ(UnpackStrip(packed, decoded), HorizonStripError::kOk);
  for (std::size_t j = 0; j < bytes.size(); ++j)
    EXPECT_EQ(decoded[j], static_cast<float>(bytes[j]));
}

TEST(PackStrip, AFlatStripAndTheFullRange) {
  const std::vector<std::uint8_t> flat(9, 42);
  std::vector<std::uint8_t> packed(PackedStripBytes(flat.size()));
  ASSERT_EQ(PackStrip(flat, packed), HorizonStripError::kOk);
  std::vector<float> decoded(flat.size());
  ASSERT_EQ(UnpackStrip(packed, decoded), HorizonStripError::kOk);
  for (const float v : decoded)
    EXPECT_EQ(v, 42.0f + 1.0f / 32.0f);  // the middle level of [41.5, 42.5]
  // 0..255: bins of 16 grey levels, 0..15 -> 7.5, 240..255 -> 247.5.
  const std::vector<std::uint8_t> full = {0, 15, 16, 128, 239, 240, 255, 255};
  packed.assign(PackedStripBytes(full.size()), 0);
  ASSERT_EQ(PackStrip(full, packed), HorizonStripError::kOk);
  decoded.assign(full.size(), 0);
  ASSERT_EQ(UnpackStrip(packed, decoded), HorizonStripError::kOk);
  EXPECT_EQ(decoded,
            (std::vector<float>{7.5f, 7.5f, 23.5f, 135.5f, 231.5f, 247.5f, 247.5f, 247.5f}));
}

TEST(PackStrip, RefusesBuffersOfAnotherLengthAndAllocatesNothing) {
  const std::vector<std::uint8_t> bytes(360, 9);
  std::vector<std::uint8_t> packed(PackedStripBytes(360) - 1, 77);
  EXPECT_EQ(PackStrip(bytes, packed), HorizonStripError::kBadOutputSize);
  EXPECT_EQ(packed, std::vector<std::uint8_t>(PackedStripBytes(360) - 1, 77));  // untouched
  std::vector<float> strip(361);
  EXPECT_EQ(UnpackStrip(packed, strip), HorizonStripError::kBadOutputSize);
  packed.assign(PackedStripBytes(360), 0);
  strip.assign(360, 0.0f);
  const AllocationScope scope;
  ASSERT_EQ(PackStrip(bytes, packed), HorizonStripError::kOk);
  ASSERT_EQ(UnpackStrip(packed, strip), HorizonStripError::kOk);
  EXPECT_EQ(scope.allocations(), 0u);
}

}  // namespace
}  // namespace skyloc::dsp
