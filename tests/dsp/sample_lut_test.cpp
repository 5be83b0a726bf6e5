#include "skyloc/dsp/sample_lut.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "skyloc/dsp/segmentation.h"
#include "skyloc/dsp/sh_grid.h"
#include "support/angles.h"

namespace skyloc::dsp {
namespace {

// An analytic sky: a spherical cap (body frame) of half-angle `alpha` around `axis`.
struct Cap {
  Eigen::Vector3d axis;
  double alpha;
  bool Contains(const Eigen::Vector3d& d) const { return d.dot(axis) > std::cos(alpha); }
  double BoundaryDistance(const Eigen::Vector3d& d) const {
    return std::fabs(std::acos(std::clamp(d.dot(axis), -1.0, 1.0)) - alpha);
  }
};

const Cap kCap{Eigen::Vector3d(std::sin(25 * kDeg) * std::cos(0.7),
                               std::sin(25 * kDeg) * std::sin(0.7), std::cos(25 * kDeg)),
               55 * kDeg};

// Draws the cap through the lens: each pixel is sky (220) when its body-frame ray is in
// the cap, ground (30) otherwise, 0 outside the image circle.
std::vector<std::uint8_t> DrawCap(const Lens& lens, const Cap& cap) {
  const int w = lens.params().width, h = lens.params().height;
  std::vector<std::uint8_t> grey(static_cast<std::size_t>(w * h));
  Eigen::Vector3d ray;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      grey[static_cast<std::size_t>(y * w + x)] =
          lens.PixelToRay(x, y, &ray) ? (cap.Contains(ray) ? 220 : 30) : 0;
  return grey;
}

Lens MakeLens(LensModel model, int w, int h, double pitch_deg) {
  LensParams p;
  p.model = model;
  p.width = w;
  p.height = h;
  p.fov_deg = 185.0;
  p.pitch_deg = pitch_deg;
  Lens lens;
  EXPECT_EQ(lens.Init(p), LensError::kOk);
  return lens;
}

// Every sample whose direction is clearly inside or outside the cap (and clearly inside
// or outside the field of view) equals the analytic answer; boundary samples are skipped.
void ExpectSamplesMatchCap(const Lens& lens, int footprint, double margin_deg) {
  ShGrid grid;
  ASSERT_EQ(grid.Init(DefaultShGridConfig(64)), ShError::kOk);
  SampleLut lut;
  SampleLutOptions options;
  options.footprint = footprint;
  ASSERT_EQ(lut.Init(lens, grid, options), SampleLutError::kOk);
  ASSERT_EQ(lut.size(), grid.sample_count());
  const std::vector<std::uint8_t> grey = DrawCap(lens, kCap);
  const ImageView image{grey.data(), lens.params().width, lens.params().height,
                        static_cast<std::size_t>(lens.params().width), PixelFormat::kGrey8};
  std::vector<float> samples(lut.size());
  ASSERT_EQ(lut.SampleImage(image, 128, samples), SampleLutError::kOk);
  std::size_t checked = 0, sky = 0;
  for (std::size_t s = 0; s < samples.size(); ++s) {
    const ShDirection dir = grid.direction(s);
    const Eigen::Vector3d d(dir.x, dir.y, dir.z);
    const Eigen::Vector3d camera = lens.camera_to_body().transpose() * d;
    const double off_axis = std::acos(std::clamp(camera(2), -1.0, 1.0));
    const bool edge_of_view = lens.params().model != LensModel::kEquirectangular &&
                              std::fabs(off_axis - lens.max_theta()) < margin_deg * kDeg;
    if (kCap.BoundaryDistance(d) < margin_deg * kDeg || edge_of_view)
      continue;
    double x, y;
    const bool expected = lens.RayToPixel(d, &x, &y) && kCap.Contains(d);
    ++checked;
    sky += expected ? 1 : 0;
    ASSERT_EQ(samples[s], expected ? 1.0f : 0.0f)
        << "sample " << s << " theta " << dir.theta << " phi " << dir.phi;
  }
  // The test means something only if most samples were checked and both classes occur.
  EXPECT_GT(checked, samples.size() * 85 / 100);
  EXPECT_GT(sky, checked / 5);
  EXPECT_LT(sky, checked * 4 / 5);
}

TEST(SampleLut, FisheyeSamplesAgreeWithTheAnalyticCap) {
  // 400 px across 185 degrees: 0.46 degrees a pixel; rounding to the nearest pixel moves
  // a sample by at most ~0.33 degrees, so a 1-degree margin isolates the boundary.
  ExpectSamplesMatchCap(MakeLens(LensModel::kEquidistant, 400, 400, 0.0), 1, 1.0);
  ExpectSamplesMatchCap(MakeLens(LensModel::kEquisolid, 480, 400, 12.0), 1, 1.0);
  // A 3x3 footprint reaches 1.5 pixels further.
  ExpectSamplesMatchCap(MakeLens(LensModel::kEquidistant, 400, 400, -8.0), 3, 1.5);
}

TEST(SampleLut, EquirectangularSamplesAgreeIncludingTheWrapColumn) {
  ExpectSamplesMatchCap(MakeLens(LensModel::kEquirectangular, 720, 360, 0.0), 1, 1.0);
  ExpectSamplesMatchCap(MakeLens(LensModel::kEquirectangular, 720, 360, 0.0), 3, 1.5);
}

// Footprint 1 reads bilinearly: a sky of the columns left of x = 96.5 (pixel centres 0..96
// sky) is, at a sub-pixel position px with x0 = floor(px) and f = px - x0, 1 for x0 <= 95,
// 1 - f for x0 = 96 and 0 beyond, whatever the row: the value the docs' formula gives,
// computed here from the lens alone. Outside the image circle the frame is bright too, and
// must still read as ground.
TEST(SampleLut, FootprintOneReadsTheSubPixelPositionBilinearly) {
  ShGrid grid;
  ASSERT_EQ(grid.Init(DefaultShGridConfig(64)), ShError::kOk);
  // The view ends half a degree (0.6 px) past the second-lowest ring: the lowest ring is
  // unseen, the one above it at the image circle's rim.
  LensParams params = MakeLens(LensModel::kEquidistant, 200, 200, 0.0).params();
  params.fov_deg = 2.0 * (grid.ring(grid.ring_count() - 2).theta / kDeg + 0.5);
  Lens lens;
  ASSERT_EQ(lens.Init(params), LensError::kOk);
  SampleLut lut;
  ASSERT_EQ(lut.Init(lens, grid, SampleLutOptions{1}), SampleLutError::kOk);
  std::vector<std::uint8_t> grey(200 * 200, 30);
  Eigen::Vector3d ray;
  for (int y = 0; y < 200; ++y)
    for (int x = 0; x < 200; ++x)
      if (x <= 96 || !lens.PixelToCameraRay(x, y, &ray))
        grey[static_cast<std::size_t>(y * 200 + x)] = 220;
  std::vector<float> samples(lut.size());
  ASSERT_EQ(lut.SampleImage({grey.data(), 200, 200, 200, PixelFormat::kGrey8}, 128, samples),
            SampleLutError::kOk);
  int on_edge = 0, checked = 0, rim = 0, unseen = 0;
  for (std::size_t s = 0; s < samples.size(); ++s) {
    const ShDirection dir = grid.direction(s);
    double px = 0, py = 0;
    if (!lens.RayToPixel(Eigen::Vector3d(dir.x, dir.y, dir.z), &px, &py) ||
        !lens.PixelToCameraRay(std::round(px), std::round(py), &ray)) {
      ASSERT_EQ(samples[s], 0.0f) << "unseen sample " << s;
      ++unseen;
      continue;
    }
    const int x0 = static_cast<int>(std::floor(px)), y0 = static_cast<int>(std::floor(py));
    bool block_seen = true;
    for (int b = 0; b < 4; ++b)
      block_seen = block_seen && lens.PixelToCameraRay(x0 + (b & 1), y0 + (b >> 1), &ray);
    if (!block_seen) {
      // The rim: the pixels outside the circle are bright but ground, so a sky sample
      // reads less than 1.
      if (x0 + 1 <= 96) {
        ASSERT_LT(samples[s], 1.0f) << "rim sample " << s;
        ++rim;
      }
      continue;
    }
    const double f = px - x0;
    const double expected = x0 <= 95 ? 1.0 : (x0 == 96 ? 1.0 - f : 0.0);
    ASSERT_NEAR(samples[s], expected, 1.0 / 128) << "sample " << s << " at " << px << ", " << py;
    on_edge += x0 == 96 ? 1 : 0;
    ++checked;
  }
  EXPECT_GT(on_edge, 20);  // the edge column is crossed by many samples (40 here)
  EXPECT_GT(checked, static_cast<int>(samples.size()) * 8 / 10);
  EXPECT_GT(rim, 10);
  EXPECT_GE(unseen, grid.longitudes());
}

// Every bilinear sample of a noisy frame is, bit for bit, the formula of
// docs/SKY_DESCRIPTOR.md ("Sampling") evaluated in floats from the lens alone: the block
// around the direction's sub-pixel position, its fractions floored to 1/256, each of its
// pixels sky when the camera sees it and it is above the threshold, top + fy (bottom -
// top). The table mixes in integers; the fractions make both exact, so they must agree to
// the bit, also at the rim and on a lens pitched off the image's centre.
TEST(SampleLut, BilinearSamplesAreTheFloatFormulaBitForBit) {
  // A 150-degree view, pitched: its rim crosses the low rings at every longitude.
  LensParams params = MakeLens(LensModel::kEquidistant, 240, 200, 9.0).params();
  params.fov_deg = 150.0;
  Lens lens;
  ASSERT_EQ(lens.Init(params), LensError::kOk);
  const int w = 240, h = 200;
  ShGrid grid;
  ASSERT_EQ(grid.Init(DefaultShGridConfig(48)), ShError::kOk);
  SampleLut lut;
  ASSERT_EQ(lut.Init(lens, grid, SampleLutOptions{1}), SampleLutError::kOk);
  std::vector<std::uint8_t> grey(static_cast<std::size_t>(w * h));
  std::uint32_t state = 777;
  for (std::uint8_t& v : grey) {
    state = state * 1664525u + 1013904223u;
    v = static_cast<std::uint8_t>(state >> 24);
  }
  constexpr int kThreshold = 100;
  std::vector<float> samples(lut.size());
  ASSERT_EQ(lut.SampleImage({grey.data(), w, h, static_cast<std::size_t>(w), PixelFormat::kGrey8},
                            kThreshold, samples),
            SampleLutError::kOk);
  Eigen::Vector3d ray;
  auto sky = [&](int x, int y) {
    return lens.PixelToCameraRay(x, y, &ray) &&
           grey[static_cast<std::size_t>(y * w + x)] > kThreshold;
  };
  int mixed = 0, rim = 0;
  for (std::size_t s = 0; s < samples.size(); ++s) {
    const ShDirection dir = grid.direction(s);
    double px = 0, py = 0;
    float expected = 0.0f;
    if (lens.RayToPixel(Eigen::Vector3d(dir.x, dir.y, dir.z), &px, &py) &&
        lens.PixelToCameraRay(static_cast<int>(std::lround(px)), static_cast<int>(std::lround(py)),
                              &ray)) {
      const double cx = std::clamp(px, 0.0, w - 1.0), cy = std::clamp(py, 0.0, h - 1.0);
      const int x0 = std::min(static_cast<int>(cx), w - 2);
      const int y0 = std::min(static_cast<int>(cy), h - 2);
      const float fx = static_cast<float>(std::min(255.0, std::floor((cx - x0) * 256.0)) / 256.0);
      const float fy = static_cast<float>(std::min(255.0, std::floor((cy - y0) * 256.0)) / 256.0);
      const float top = (sky(x0, y0) ? 1.0f - fx : 0.0f) + (sky(x0 + 1, y0) ? fx : 0.0f);
      const float bottom = (sky(x0, y0 + 1) ? 1.0f - fx : 0.0f) + (sky(x0 + 1, y0 + 1) ? fx : 0.0f);
      expected = top + fy * (bottom - top);
      bool whole_block_seen = true;
      for (int b = 0; b < 4; ++b)
        whole_block_seen =
            whole_block_seen && lens.PixelToCameraRay(x0 + (b & 1), y0 + (b >> 1), &ray);
      rim += whole_block_seen ? 0 : 1;
    }
    ASSERT_EQ(samples[s], expected) << "sample " << s;
    mixed += (expected > 0.0f && expected < 1.0f) ? 1 : 0;
  }
  EXPECT_GT(mixed, static_cast<int>(samples.size() / 4));  // not trivially 0 or 1
  EXPECT_GT(rim, 10);  // blocks with a pixel outside the view (21 here)
}

TEST(SampleLut, FootprintAveragesAndOutsideTheViewIsGround) {
  const Lens lens = MakeLens(LensModel::kEquidistant, 300, 300, 0.0);
  ShGrid grid;
  ASSERT_EQ(grid.Init(DefaultShGridConfig(32)), ShError::kOk);
  SampleLut lut;
  ASSERT_EQ(lut.Init(lens, grid, SampleLutOptions{3}), SampleLutError::kOk);
  // An all-sky frame: interior samples are 1, samples at the edge of the circle have some
  // taps outside it (fractions of 1/9), and nothing exceeds 1.
  std::vector<std::uint8_t> white(300 * 300, 255);
  std::vector<float> samples(lut.size());
  ASSERT_EQ(lut.SampleImage({white.data(), 300, 300, 300, PixelFormat::kGrey8}, 128, samples),
            SampleLutError::kOk);
  int partial = 0;
  for (float s : samples) {
    EXPECT_GE(s, 0.0f);
    EXPECT_LE(s, 1.0f);
    const float ninths = s * 9.0f;
    EXPECT_NEAR(ninths, std::round(ninths), 1e-5f);
    partial += (s > 0.0f && s < 1.0f) ? 1 : 0;
  }
  EXPECT_GT(lut.visible_fraction(), 0.99);  // 185 degrees sees the whole upper hemisphere
  EXPECT_GT(std::count(samples.begin(), samples.end(), 1.0f),
            static_cast<std::ptrdiff_t>(samples.size() * 9 / 10));

  // A 120-degree lens does not see the low rings: they are ground even in an all-sky frame.
  LensParams narrow = lens.params();
  narrow.fov_deg = 120.0;
  Lens narrow_lens;
  ASSERT_EQ(narrow_lens.Init(narrow), LensError::kOk);
  ASSERT_EQ(lut.Init(narrow_lens, grid, SampleLutOptions{1}), SampleLutError::kOk);
  ASSERT_EQ(lut.SampleImage({white.data(), 300, 300, 300, PixelFormat::kGrey8}, 128, samples),
            SampleLutError::kOk);
  for (std::size_t s = 0; s < samples.size(); ++s) {
    if (grid.direction(s).theta > 61 * kDeg) {
      ASSERT_EQ(samples[s], 0.0f) << s;
    } else if (grid.direction(s).theta < 59 * kDeg) {
      ASSERT_EQ(samples[s], 1.0f) << s;
    }
  }
  EXPECT_LT(lut.visible_fraction(), 0.75);
}

TEST(SampleLut, DirectThresholdingEqualsSamplingTheMaskInEveryFormat) {
  const Lens lens = MakeLens(LensModel::kEquidistant, 320, 240, 5.0);
  ShGrid grid;
  ASSERT_EQ(grid.Init(DefaultShGridConfig(48)), ShError::kOk);
  // Noisy bytes, so many pixels sit near the threshold; each format reads them differently.
  // Bands of 960 bytes (a row of RGB, 3 of grey) alternate between a dark and a bright
  // class, so every format sees sky and ground (a frame of one class would have none,
  // dsp::SeparatesSkyFromGround).
  std::vector<std::uint8_t> bytes(320 * 240 * 3);
  std::uint32_t state = 12345;
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    state = state * 1664525u + 1013904223u;
    const std::uint32_t noise = (state >> 24) * 81u / 256u;  // 0..80
    bytes[i] = static_cast<std::uint8_t>((i / 960) % 2 == 0 ? 20u + noise : 140u + noise);
  }
  const ImageView images[] = {{bytes.data(), 320, 240, 320 * 3, PixelFormat::kRgb24},
                              {bytes.data(), 320, 240, 320 * 3, PixelFormat::kBgr24},
                              {bytes.data(), 320, 240, 320 * 2, PixelFormat::kYuyv},
                              {bytes.data(), 320, 240, 320, PixelFormat::kGrey8}};
  for (int footprint : {1, 3}) {
    SampleLut lut;
    ASSERT_EQ(lut.Init(lens, grid, SampleLutOptions{footprint}), SampleLutError::kOk);
    for (const ImageView& image : images) {
      SkySegmenter seg;
      ASSERT_EQ(seg.Init(lens, {}), SegmentationError::kOk);
      std::vector<std::uint8_t> mask(320 * 240);
      SegmentationResult r;
      ASSERT_EQ(seg.Segment(image, {mask.data(), 320, 240, 320, PixelFormat::kGrey8}, &r),
                SegmentationError::kOk);
      std::vector<float> direct(lut.size()), via_mask(lut.size());
      ASSERT_EQ(lut.SampleImage(image, r.threshold, direct), SampleLutError::kOk);
      ASSERT_EQ(lut.SampleMask({mask.data(), 320, 240, 320, PixelFormat::kGrey8}, via_mask),
                SampleLutError::kOk);
      EXPECT_EQ(direct, via_mask) << "footprint " << footprint << " "
                                  << PixelFormatName(image.format);
      // Not trivially all-ground or all-sky.
      const auto sky =
          std::count_if(direct.begin(), direct.end(), [](float v) { return v >= 0.5f; });
      EXPECT_GT(sky, static_cast<std::ptrdiff_t>(direct.size() / 10));
      EXPECT_LT(sky, static_cast<std::ptrdiff_t>(direct.size() * 9 / 10));
    }
  }
}

TEST(SampleLut, BadArgumentsAreRejected) {
  const Lens lens = MakeLens(LensModel::kEquidistant, 100, 100, 0.0);
  SampleLut lut;
  const double rings[] = {0.1, 0.5};
  EXPECT_EQ(lut.Init(lens, rings, 16, SampleLutOptions{2}), SampleLutError::kBadFootprint);
  EXPECT_EQ(lut.Init(lens, rings, 0, {}), SampleLutError::kBadGrid);
  const double bad_rings[] = {-0.1};
  EXPECT_EQ(lut.Init(lens, bad_rings, 16, {}), SampleLutError::kBadGrid);
  ASSERT_EQ(lut.Init(lens, rings, 16, {}), SampleLutError::kOk);
  std::vector<std::uint8_t> frame(100 * 100);
  std::vector<float> samples(31);
  EXPECT_EQ(lut.SampleImage({frame.data(), 100, 100, 100, PixelFormat::kGrey8}, 1, samples),
            SampleLutError::kBadOutputSize);
  samples.resize(32);
  EXPECT_EQ(lut.SampleImage({frame.data(), 99, 100, 100, PixelFormat::kGrey8}, 1, samples),
            SampleLutError::kSizeMismatch);
}

}  // namespace
}  // namespace skyloc::dsp
