#include "skyloc/dsp/segmentation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "skyloc/platform/alloc_counter.h"
#include "support/fisheye_lens.h"

namespace skyloc::dsp {
namespace {

using testing::FisheyeLens;

constexpr int kSize = 200;

// Ground truth of a synthetic scene: sky is the cap within 50 degrees of the zenith
// tilted 20 degrees towards +x, plus a bright square "cloud-free patch" that is ground
// (a building) — the mask then has two boundaries. Outside the image circle: none.
bool TrueSky(const Lens& lens, int x, int y) {
  Eigen::Vector3d ray;
  if (!lens.PixelToRay(x, y, &ray))
    return false;
  const Eigen::Vector3d axis(std::sin(0.35), 0.0, std::cos(0.35));
  const bool building = x > 120 && x < 150 && y > 40 && y < 90;
  return ray.dot(axis) > std::cos(50.0 * std::numbers::pi / 180.0) && !building;
}

// Grey frame: sky ~ N(200, 15), ground ~ N(50, 15); outside the circle bright noise that
// must not count (it would pull Otsu's threshold if it did).
std::vector<std::uint8_t> BimodalFrame(const Lens& lens, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> sky(200, 15), ground(50, 15);
  std::uniform_int_distribution<int> outside(120, 255);
  std::vector<std::uint8_t> grey(kSize * kSize);
  Eigen::Vector3d ray;
  for (int y = 0; y < kSize; ++y) {
    for (int x = 0; x < kSize; ++x) {
      double v = 0;
      if (!lens.PixelToCameraRay(x, y, &ray))
        v = outside(rng);
      else
        v = TrueSky(lens, x, y) ? sky(rng) : ground(rng);
      grey[static_cast<std::size_t>(y * kSize + x)] =
          static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
    }
  }
  return grey;
}

ImageView GreyView(const std::vector<std::uint8_t>& g) {
  return {g.data(), kSize, kSize, kSize, PixelFormat::kGrey8};
}

TEST(SkySegmenter, RowRunsAreExactlyTheVisiblePixels) {
  const Lens lens = FisheyeLens(220, 180);
  SkySegmenter seg;
  ASSERT_EQ(seg.Init(lens, {}), SegmentationError::kOk);
  Eigen::Vector3d ray;
  for (int y = 0; y < 180; ++y) {
    const RowSpan run = seg.rows()[static_cast<std::size_t>(y)];
    for (int x = 0; x < 220; ++x)
      ASSERT_EQ(lens.PixelToCameraRay(x, y, &ray), x >= run.begin && x < run.end) << x << "," << y;
  }
}

TEST(SkySegmenter, BimodalImageSegmentsAbove99PercentAndOutsideIsGround) {
  const Lens lens = FisheyeLens(kSize, kSize);
  SkySegmenter seg;
  ASSERT_EQ(seg.Init(lens, {}), SegmentationError::kOk);
  const std::vector<std::uint8_t> grey = BimodalFrame(lens, 3);
  std::vector<std::uint8_t> mask(kSize * kSize, 77);
  SegmentationResult r;
  ASSERT_EQ(
      seg.Segment(GreyView(grey), {mask.data(), kSize, kSize, kSize, PixelFormat::kGrey8}, &r),
      SegmentationError::kOk);
  EXPECT_GT(r.threshold, 80);
  EXPECT_LT(r.threshold, 170);
  std::size_t correct = 0, inside = 0, sky = 0;
  Eigen::Vector3d ray;
  for (int y = 0; y < kSize; ++y) {
    for (int x = 0; x < kSize; ++x) {
      const std::uint8_t m = mask[static_cast<std::size_t>(y * kSize + x)];
      ASSERT_TRUE(m == kMaskSky || m == kMaskGround);
      if (!lens.PixelToCameraRay(x, y, &ray)) {
        ASSERT_EQ(m, kMaskGround) << "outside the circle at " << x << "," << y;
        continue;
      }
      ++inside;
      sky += m == kMaskSky ? 1u : 0u;
      correct += ((m == kMaskSky) == TrueSky(lens, x, y)) ? 1u : 0u;
    }
  }
  EXPECT_GT(static_cast<double>(correct) / static_cast<double>(inside), 0.99);
  EXPECT_EQ(r.circle_pixels, inside);
  EXPECT_DOUBLE_EQ(r.sky_fraction, static_cast<double>(sky) / static_cast<double>(inside));
  EXPECT_GT(r.separability, 0.8);
}

// One grey level plus sensor noise over the whole frame, clipped to 0..255: what a blind
// camera sees (lens cap: black; saturated sensor: white; fog or a grey card: grey).
std::vector<std::uint8_t> BlindFrame(double level, double noise_sigma, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_sigma > 0 ? noise_sigma : 1.0);
  std::vector<std::uint8_t> grey(kSize * kSize);
  for (std::uint8_t& v : grey) {
    const double x = level + (noise_sigma > 0 ? noise(rng) : 0.0);
    v = static_cast<std::uint8_t>(std::clamp(std::lround(x), 0L, 255L));
  }
  return grey;
}

TEST(SkySegmenter, ABlindFrameHasNoSkyAndANormalFrameHas) {
  const Lens lens = FisheyeLens(kSize, kSize);
  SkySegmenter seg;
  ASSERT_EQ(seg.Init(lens, {}), SegmentationError::kOk);
  std::vector<std::uint8_t> mask(kSize * kSize, 77);
  const MutableImageView mask_view{mask.data(), kSize, kSize, kSize, PixelFormat::kGrey8};
  struct Blind {
    const char* what;
    double level, noise;
  };
  for (const Blind& b :
       {Blind{"uniform grey", 128, 0}, Blind{"all black", 0, 0}, Blind{"all white", 255, 0},
        Blind{"lens cap, noise 1", 0, 1}, Blind{"lens cap, noise 3", 0, 3},
        Blind{"lens cap, noise 8", 0, 8}, Blind{"saturated, noise 2", 255, 2},
        Blind{"grey, noise 2", 128, 2}, Blind{"grey, noise 20", 128, 20}}) {
    SCOPED_TRACE(b.what);
    const std::vector<std::uint8_t> grey = BlindFrame(b.level, b.noise, 11);
    SegmentationResult r;
    ASSERT_EQ(seg.Segment(GreyView(grey), mask_view, &r), SegmentationError::kOk);
    EXPECT_FALSE(r.sky_contrast);
    // Not all sky, and not half sky either: no sky at all, the mask all ground.
    EXPECT_EQ(r.threshold, kNoSkyThreshold);
    EXPECT_EQ(r.sky_fraction, 0.0);
    EXPECT_EQ(std::count(mask.begin(), mask.end(), kMaskSky), 0);
  }
  // Sky N(200, 15) over ground N(50, 15): the frame as it was, with contrast.
  const std::vector<std::uint8_t> grey = BimodalFrame(lens, 3);
  SegmentationResult r;
  ASSERT_EQ(seg.Segment(GreyView(grey), mask_view, &r), SegmentationError::kOk);
  EXPECT_TRUE(r.sky_contrast);
  EXPECT_EQ(r.threshold, OtsuThreshold(seg.histogram()).threshold);
  EXPECT_GT(r.sky_fraction, 0.2);
  EXPECT_LT(r.sky_fraction, 0.8);

  // A fixed threshold does not make a blind frame sky either.
  SkySegmenter fixed;
  SegmentationOptions options;
  options.fixed_threshold = 128;
  ASSERT_EQ(fixed.Init(lens, options), SegmentationError::kOk);
  const std::vector<std::uint8_t> white = BlindFrame(255, 0, 1);
  ASSERT_EQ(fixed.Threshold(GreyView(white), &r), SegmentationError::kOk);
  EXPECT_FALSE(r.sky_contrast);
  EXPECT_EQ(r.sky_fraction, 0.0);
  ASSERT_EQ(fixed.Threshold(GreyView(grey), &r), SegmentationError::kOk);
  EXPECT_TRUE(r.sky_contrast);
  EXPECT_EQ(r.threshold, 128);
}

TEST(SkySegmenter, ColourFormatsUseTheChannelMeanAndYuyvTheLuma) {
  const Lens lens = FisheyeLens(kSize, kSize);
  SkySegmenter seg;
  ASSERT_EQ(seg.Init(lens, {}), SegmentationError::kOk);
  const std::vector<std::uint8_t> grey = BimodalFrame(lens, 4);
  // RGB whose channel mean is the grey value; BGR the same bytes reversed per pixel;
  // YUYV with the grey value as Y and chroma bytes that would mislead a wrong stride.
  std::vector<std::uint8_t> rgb(grey.size() * 3), bgr(grey.size() * 3), yuyv(grey.size() * 2);
  std::mt19937 rng(9);
  for (std::size_t i = 0; i < grey.size(); ++i) {
    const int g = grey[i];
    const int d = std::min({g, 255 - g, 30});
    const int spread = d > 0 ? static_cast<int>(rng() % static_cast<unsigned>(d + 1)) : 0;
    rgb[3 * i] = static_cast<std::uint8_t>(g - spread);
    rgb[3 * i + 1] = static_cast<std::uint8_t>(g);
    rgb[3 * i + 2] = static_cast<std::uint8_t>(g + spread);
    bgr[3 * i] = rgb[3 * i + 2];
    bgr[3 * i + 1] = rgb[3 * i + 1];
    bgr[3 * i + 2] = rgb[3 * i];
    yuyv[2 * i] = static_cast<std::uint8_t>(g);
    yuyv[2 * i + 1] = static_cast<std::uint8_t>(255 - g);
  }
  std::vector<std::uint8_t> expected(grey.size()), mask(grey.size());
  SegmentationResult want, got;
  ASSERT_EQ(seg.Segment(GreyView(grey), {expected.data(), kSize, kSize, kSize, PixelFormat::kGrey8},
                        &want),
            SegmentationError::kOk);
  const MutableImageView mask_view{mask.data(), kSize, kSize, kSize, PixelFormat::kGrey8};
  const ImageView colour[] = {{rgb.data(), kSize, kSize, 3 * kSize, PixelFormat::kRgb24},
                              {bgr.data(), kSize, kSize, 3 * kSize, PixelFormat::kBgr24},
                              {yuyv.data(), kSize, kSize, 2 * kSize, PixelFormat::kYuyv}};
  for (const ImageView& image : colour) {
    ASSERT_EQ(seg.Segment(image, mask_view, &got), SegmentationError::kOk);
    EXPECT_EQ(got.threshold, want.threshold) << PixelFormatName(image.format);
    EXPECT_EQ(mask, expected) << PixelFormatName(image.format);
    EXPECT_EQ(PixelValue(image, 17, 101), grey[101 * kSize + 17]);
  }
}

TEST(SkySegmenter, FixedThresholdAndStridedHistogram) {
  const Lens lens = FisheyeLens(kSize, kSize);
  const std::vector<std::uint8_t> grey = BimodalFrame(lens, 5);
  SkySegmenter fixed;
  SegmentationOptions options;
  options.fixed_threshold = 40;  // most ground is brighter than 40: far more "sky"
  ASSERT_EQ(fixed.Init(lens, options), SegmentationError::kOk);
  SegmentationResult low, otsu;
  ASSERT_EQ(fixed.Threshold(GreyView(grey), &low), SegmentationError::kOk);
  EXPECT_EQ(low.threshold, 40);
  EXPECT_EQ(low.separability, 0.0);
  SkySegmenter normal;
  ASSERT_EQ(normal.Init(lens, {}), SegmentationError::kOk);
  ASSERT_EQ(normal.Threshold(GreyView(grey), &otsu), SegmentationError::kOk);
  EXPECT_GT(low.sky_fraction, otsu.sky_fraction + 0.2);

  // Every 2nd row and column: a quarter of the pixels, nearly the same answer.
  SkySegmenter strided;
  options = {};
  options.histogram_step = 2;
  ASSERT_EQ(strided.Init(lens, options), SegmentationError::kOk);
  SegmentationResult s;
  ASSERT_EQ(strided.Threshold(GreyView(grey), &s), SegmentationError::kOk);
  EXPECT_NEAR(s.circle_pixels, otsu.circle_pixels / 4.0, otsu.circle_pixels * 0.02);
  EXPECT_NEAR(s.sky_fraction, otsu.sky_fraction, 0.01);
  EXPECT_NEAR(s.threshold, otsu.threshold, 15);

  options.histogram_step = 0;
  EXPECT_EQ(strided.Init(lens, options), SegmentationError::kBadOptions);
  options = {};
  options.fixed_threshold = 255;
  EXPECT_EQ(strided.Init(lens, options), SegmentationError::kBadOptions);
}

TEST(SkySegmenter, WrongSizesAreRejected) {
  const Lens lens = FisheyeLens(kSize, kSize);
  SkySegmenter seg;
  ASSERT_EQ(seg.Init(lens, {}), SegmentationError::kOk);
  std::vector<std::uint8_t> buffer(kSize * kSize);
  SegmentationResult r;
  EXPECT_EQ(seg.Threshold({buffer.data(), kSize - 1, kSize, kSize, PixelFormat::kGrey8}, &r),
            SegmentationError::kSizeMismatch);
  EXPECT_EQ(seg.Segment({buffer.data(), kSize, kSize, kSize, PixelFormat::kGrey8},
                        {buffer.data(), kSize, kSize, kSize, PixelFormat::kRgb24}, &r),
            SegmentationError::kBadMaskFormat);
}

TEST(SkySegmenter, FramePathAllocatesNothing) {
  ASSERT_TRUE(AllocationCounterActive());
  const Lens lens = FisheyeLens(kSize, kSize);
  SkySegmenter seg;
  ASSERT_EQ(seg.Init(lens, {}), SegmentationError::kOk);
  const std::vector<std::uint8_t> grey = BimodalFrame(lens, 6);
  std::vector<std::uint8_t> mask(grey.size());
  SegmentationResult r;
  AllocationScope scope;
  for (int i = 0; i < 50; ++i) {
    ASSERT_EQ(
        seg.Segment(GreyView(grey), {mask.data(), kSize, kSize, kSize, PixelFormat::kGrey8}, &r),
        SegmentationError::kOk);
  }
  EXPECT_EQ(scope.allocations(), 0u);
}

}  // namespace
}  // namespace skyloc::dsp
