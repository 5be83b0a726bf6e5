#include "skyloc/dsp/sky_descriptor.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "skyloc/platform/alloc_counter.h"
#include "support/angles.h"
#include "support/fisheye_lens.h"

namespace skyloc::dsp {
namespace {

using testing::FisheyeLens;

// A street canyon, body frame: sky where the elevation clears two walls running along
// `heading`, plus a tree (a cap of ground) over one pavement. Rotating the heading yaws the
// whole sky about the zenith.
bool CanyonSky(const Eigen::Vector3d& d, double heading, double wall_scale) {
  const Eigen::Vector3d across(-std::sin(heading), std::cos(heading), 0.0);
  const double side = d.dot(across);
  if (d(2) <= 0.0)
    return false;
  const double wall = (side > 0 ? 1.3 : 0.8) * wall_scale;  // height over distance, each side
  if (std::fabs(side) * wall > d(2))
    return false;
  const Eigen::Vector3d tree = Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()) *
                               Eigen::Vector3d(std::cos(40 * kDeg), 0.0, std::sin(40 * kDeg));
  return d.dot(tree) < std::cos(15 * kDeg);
}

// Draws a sky (210) over ground (40) through the lens, 5 outside its view.
template <typename Sky>
std::vector<std::uint8_t> DrawSky(const Lens& lens, const Sky& is_sky) {
  const int w = lens.params().width, h = lens.params().height;
  std::vector<std::uint8_t> grey(static_cast<std::size_t>(w * h));
  Eigen::Vector3d ray;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      grey[static_cast<std::size_t>(y * w + x)] =
          lens.PixelToRay(x, y, &ray) ? (is_sky(ray) ? 210 : 40) : 5;
  return grey;
}

std::vector<std::uint8_t> DrawCanyon(const Lens& lens, double heading, double wall_scale = 1.0) {
  return DrawSky(lens, [&](const Eigen::Vector3d& d) { return CanyonSky(d, heading, wall_scale); });
}

double RelativeL2(const std::vector<float>& a, const std::vector<float>& b) {
  double diff = 0, norm = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double x = a[i], y = b[i];
    diff += (x - y) * (x - y);
    norm += x * x;
  }
  return std::sqrt(diff / norm);
}

TEST(SkyDescriptor, YawChangesTheSpectrumByUnderOnePercent) {
  const Lens lens = FisheyeLens(480, 480);
  SkyDescriptor descriptor;
  SkyDescriptorOptions options;
  options.bands = 32;
  // Twice the rings and longitudes the 32 bands need: a hard-edged mask is not band-limited,
  // and on the minimal grid its edge aliases into a few percent of yaw dependence.
  options.grid = DefaultShGridConfig(64);
  ASSERT_TRUE(descriptor.Init(lens, options).ok());
  std::vector<float> a0(32), a1(32), other(32);
  const std::vector<std::uint8_t> f0 = DrawCanyon(lens, 0.0);
  const std::vector<std::uint8_t> f1 = DrawCanyon(lens, 37 * kDeg);
  SegmentationResult r0, r1;
  ASSERT_TRUE(descriptor.Compute({f0.data(), 480, 480, 480, PixelFormat::kGrey8}, a0, &r0).ok());
  ASSERT_TRUE(descriptor.Compute({f1.data(), 480, 480, 480, PixelFormat::kGrey8}, a1, &r1).ok());
  EXPECT_LT(RelativeL2(a0, a1), 0.01);
  EXPECT_NEAR(r0.sky_fraction, r1.sky_fraction, 0.005);
  EXPECT_GE(r0.threshold, 40);
  EXPECT_LT(r0.threshold, 210);
  // a_0 = sky solid angle / sqrt(4 pi): compare with the sampled hemisphere's sky share.
  EXPECT_GT(a0[0], 0.1f);

  // A different place (narrower canyon: higher walls) is much farther away than the yaw.
  std::vector<std::uint8_t> f2 = f0;
  Eigen::Vector3d ray;
  for (int y = 0; y < 480; ++y)
    for (int x = 0; x < 480; ++x)
      if (lens.PixelToRay(x, y, &ray) && std::fabs(ray(1)) * 2.5 > ray(2) && ray(2) > 0)
        f2[static_cast<std::size_t>(y * 480 + x)] = 40;
  ASSERT_TRUE(descriptor.Compute({f2.data(), 480, 480, 480, PixelFormat::kGrey8}, other).ok());
  EXPECT_GT(DescriptorDistance(a0, other), 5 * DescriptorDistance(a0, a1));
}

// At the frame size a small robot's loop runs (160 x 120, 1.5 degrees a pixel) a yaw of a
// fraction of a pixel moves the mask's edge across pixel centres. Read at the nearest
// pixel, a sample flips whole as the edge passes it, and the spectrum jumps; read
// bilinearly it follows the edge. The reference is the spectrum's invariance to yaw.
TEST(SkyDescriptor, SubPixelYawsBarelyMoveTheSpectrumAtLowResolution) {
  const Lens lens = FisheyeLens(160, 120);
  SkyDescriptor descriptor;
  SkyDescriptorOptions options;
  options.bands = 120;
  ASSERT_TRUE(descriptor.Init(lens, options).ok());
  std::vector<float> a0(120), a(120), other(120);
  const std::vector<std::uint8_t> f0 = DrawCanyon(lens, 0.0);
  ASSERT_TRUE(descriptor.Compute({f0.data(), 160, 120, 160, PixelFormat::kGrey8}, a0).ok());
  double worst = 0.0, sum = 0.0;
  int steps = 0;
  for (double yaw = 0.25; yaw <= 3.0; yaw += 0.25, ++steps) {
    const std::vector<std::uint8_t> f = DrawCanyon(lens, yaw * kDeg);
    ASSERT_TRUE(descriptor.Compute({f.data(), 160, 120, 160, PixelFormat::kGrey8}, a).ok());
    worst = std::max(worst, RelativeL2(a0, a));
    sum += RelativeL2(a0, a);
  }
  const std::vector<std::uint8_t> f2 = DrawCanyon(lens, 0.0, 1.6);
  ASSERT_TRUE(descriptor.Compute({f2.data(), 160, 120, 160, PixelFormat::kGrey8}, other).ok());
  // Measured (x86-64): bilinear mean 0.47 %, worst 0.59 %; the nearest pixel (the read
  // before 2026-11-26) mean 0.81 %, worst 0.96 %. Another place is 25 % away.
  EXPECT_LT(sum / steps, 0.006);
  EXPECT_LT(worst, 0.0075);
  EXPECT_GT(RelativeL2(a0, other), 0.15);
}

// A canopy: the sky seen through leaves, fixed in the world and yawed by `heading` about
// the zenith. 400 round leaves of 1.5-5 degrees radius at elevations 15-85 degrees, from a
// fixed linear congruential sequence (the same canopy in every run and on every machine).
std::vector<std::uint8_t> DrawCanopy(const Lens& lens, double heading) {
  std::vector<Eigen::Vector3d> centres;
  std::vector<double> cos_radius;
  std::uint32_t state = 12345;
  auto next = [&state] {
    state = state * 1664525u + 1013904223u;
    return static_cast<double>(state >> 8) / 16777216.0;
  };
  for (int k = 0; k < 400; ++k) {
    const double azimuth = 2 * std::numbers::pi * next() + heading;
    const double elevation = (15 + 70 * next()) * kDeg;
    centres.emplace_back(std::cos(elevation) * std::cos(azimuth),
                         std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    cos_radius.push_back(std::cos((1.5 + 3.5 * next()) * kDeg));
  }
  return DrawSky(lens, [&](const Eigen::Vector3d& d) {
    if (d(2) <= 0.0)
      return false;
    for (std::size_t k = 0; k < centres.size(); ++k)
      if (d.dot(centres[k]) > cos_radius[k])
        return false;
    return true;
  });
}

// Why the firmware samples L bands on the grid for 1.5 L (OversampledShGridConfig) rather
// than the minimal grid for L: a canopy's leaf edges are not band-limited, and on the
// minimal grid what lies above the grid's limit folds into the kept bands by an amount that
// depends on where the edges fall between samples, so a yaw (to which the spectrum of the
// sky is invariant: the reference) moves it. The firmware's 640x480 camera and bands (64),
// and the paper's 120, yawed by angles that are not multiples of either grid's longitude
// step.
TEST(SkyDescriptor, OversampledGridMovesLessWithAYawThanTheMinimalGrid) {
  const Lens lens = FisheyeLens(640, 480);
  const std::vector<std::uint8_t> f0 = DrawCanopy(lens, 0.0);
  constexpr double kYawsDeg[] = {7.3, 19.1, 37.7, 53.9, 71.3};
  std::vector<std::vector<std::uint8_t>> yawed;
  for (double yaw : kYawsDeg)
    yawed.push_back(DrawCanopy(lens, yaw * kDeg));
  const std::vector<std::uint8_t> street = DrawCanyon(lens, 0.0, 0.3);
  EXPECT_EQ(OversampledShGridConfig(64).rings, 48);
  EXPECT_EQ(OversampledShGridConfig(64).longitudes, 256);
  EXPECT_EQ(OversampledShGridConfig(120).rings, 90);
  EXPECT_EQ(OversampledShGridConfig(120).longitudes, 512);
  for (const int bands : {64, 120}) {
    const ShGridConfig grids[2] = {DefaultShGridConfig(bands), OversampledShGridConfig(bands)};
    double change[2] = {0, 0}, other_place[2] = {0, 0};
    for (int g = 0; g < 2; ++g) {
      SkyDescriptorOptions options;
      options.bands = bands;
      options.grid = grids[g];
      options.normalisation = AmplitudeNormalisation::kUnitL2;
      SkyDescriptor descriptor;
      ASSERT_TRUE(descriptor.Init(lens, options).ok());
      const std::size_t n = static_cast<std::size_t>(bands);
      std::vector<float> a0(n), a(n);
      ASSERT_TRUE(descriptor.Compute({f0.data(), 640, 480, 640, PixelFormat::kGrey8}, a0).ok());
      for (const std::vector<std::uint8_t>& f : yawed) {
        ASSERT_TRUE(descriptor.Compute({f.data(), 640, 480, 640, PixelFormat::kGrey8}, a).ok());
        change[g] += RelativeL2(a0, a) / std::size(kYawsDeg);
      }
      ASSERT_TRUE(descriptor.Compute({street.data(), 640, 480, 640, PixelFormat::kGrey8}, a).ok());
      other_place[g] = RelativeL2(a0, a);
      std::printf(
          "  %3d bands on %d x %d: yaw moves the spectrum by %.4f (relative L2, mean "
          "of %zu), an open street is %.4f away\n",
          bands, grids[g].rings, grids[g].longitudes, change[g], std::size(kYawsDeg),
          other_place[g]);
    }
    EXPECT_LT(change[1], 0.5 * change[0]) << bands << " bands";
    EXPECT_GT(other_place[1], 10 * change[1]) << bands << " bands";
  }
}

// The tilt tests: a 480x480 185-degree fisheye whose mount angles draw a tilted camera,
// and a 32-band descriptor on the grid for 64 bands (the mask edge does not alias).
LensParams TiltDrawingLens() {
  LensParams p;
  p.width = p.height = 480;
  p.fov_deg = 185.0;
  return p;
}

SkyDescriptorOptions TiltTestOptions() {
  SkyDescriptorOptions options;
  options.bands = 32;
  options.grid = DefaultShGridConfig(64);
  return options;
}

// The camera tilts but the descriptor does not know (mount angles 0): the hemisphere it
// sees changes, so the spectrum changes. Reported next to the distance to another place,
// as the issue asks; asserted only where the answer is clear (10 degrees is much closer
// than another place, and the change grows with the tilt).
TEST(SkyDescriptor, UnknownTiltReportedAgainstADifferentPlace) {
  LensParams drawn = TiltDrawingLens();
  Lens upright;
  ASSERT_EQ(upright.Init(drawn), LensError::kOk);
  const SkyDescriptorOptions options = TiltTestOptions();
  SkyDescriptor descriptor;
  ASSERT_TRUE(descriptor.Init(upright, options).ok());
  std::vector<float> level(32), tilted(32), other(32);
  const std::vector<std::uint8_t> f0 = DrawCanyon(upright, 0.0);
  ASSERT_TRUE(descriptor.Compute({f0.data(), 480, 480, 480, PixelFormat::kGrey8}, level).ok());
  const std::vector<std::uint8_t> place = DrawCanyon(upright, 0.0, 2.5);
  ASSERT_TRUE(descriptor.Compute({place.data(), 480, 480, 480, PixelFormat::kGrey8}, other).ok());
  const double other_place = RelativeL2(level, other);
  std::printf("  different place: relative L2 %.4f\n", other_place);
  double previous = 0.0;
  for (double tilt : {10.0, 20.0, 40.0, 60.0}) {
    drawn.pitch_deg = tilt;
    Lens tilted_lens;
    ASSERT_EQ(tilted_lens.Init(drawn), LensError::kOk);
    const std::vector<std::uint8_t> f = DrawCanyon(tilted_lens, 0.0);
    ASSERT_TRUE(descriptor.Compute({f.data(), 480, 480, 480, PixelFormat::kGrey8}, tilted).ok());
    const double change = RelativeL2(level, tilted);
    std::printf("  unknown tilt %2.0f deg: relative L2 %.4f\n", tilt, change);
    EXPECT_GT(change, previous);
    previous = change;
    if (tilt == 10.0) {
      EXPECT_LT(change, other_place / 2);
    }
  }
}

// Why the product divides the spectrum by its L2 norm ([descriptor] normalisation,
// docs/SKY_DESCRIPTOR.md): a tilt the descriptor does not know moves sky out of the
// hemisphere on one side and in on the other, and it changes how much sky is seen, which
// scales every amplitude (for a binary mask sum a_l^2 is the sky's solid angle, Parseval).
// Normalised, the change a tilt makes shrinks against the difference between two places,
// as the matcher measures it (mean absolute difference).
TEST(SkyDescriptor, UnitL2MakesAnUnknownTiltCloserThanAnotherPlace) {
  LensParams drawn = TiltDrawingLens();
  Lens upright;
  ASSERT_EQ(upright.Init(drawn), LensError::kOk);
  const std::vector<std::uint8_t> level_image = DrawCanyon(upright, 0.0);
  const std::vector<std::uint8_t> place_image = DrawCanyon(upright, 0.0, 1.6);
  for (double tilt : {10.0, 15.0, 20.0}) {
    drawn.pitch_deg = tilt;
    Lens tilted_lens;
    ASSERT_EQ(tilted_lens.Init(drawn), LensError::kOk);
    const std::vector<std::uint8_t> tilted_image = DrawCanyon(tilted_lens, 0.0);
    double ratio[2] = {0, 0};
    int i = 0;
    for (const AmplitudeNormalisation n :
         {AmplitudeNormalisation::kNone, AmplitudeNormalisation::kUnitL2}) {
      SkyDescriptorOptions options = TiltTestOptions();
      options.normalisation = n;
      SkyDescriptor descriptor;
      ASSERT_TRUE(descriptor.Init(upright, options).ok());
      std::vector<float> level(32), tilted(32), place(32);
      ASSERT_TRUE(
          descriptor.Compute({level_image.data(), 480, 480, 480, PixelFormat::kGrey8}, level).ok());
      ASSERT_TRUE(
          descriptor.Compute({tilted_image.data(), 480, 480, 480, PixelFormat::kGrey8}, tilted)
              .ok());
      ASSERT_TRUE(
          descriptor.Compute({place_image.data(), 480, 480, 480, PixelFormat::kGrey8}, place).ok());
      ratio[i++] = DescriptorDistance(level, tilted) / DescriptorDistance(level, place);
    }
    std::printf("  tilt %2.0f deg: tilt / other place, none %.3f, unit_l2 %.3f\n", tilt, ratio[0],
                ratio[1]);
    EXPECT_LT(ratio[1], ratio[0]) << "tilt " << tilt;
  }
}

// The cap tests' measure: the canyon (walls `walls` times the test's) described level, at
// another place (walls `other_walls`), and tilted by (roll, pitch) with the true zenith;
// the tilt's change and the other place's distance as relative L2.
class CapAgainstAnotherPlace {
 public:
  void Init(double cap_elevation_deg, double walls, double other_walls) {
    drawn_ = TiltDrawingLens();
    ASSERT_EQ(upright_.Init(drawn_), LensError::kOk);
    SkyDescriptorOptions options = TiltTestOptions();
    options.cap = {true, cap_elevation_deg, 10};
    ASSERT_TRUE(descriptor_.Init(upright_, options).ok());
    walls_ = walls;
    const std::vector<std::uint8_t> f0 = DrawCanyon(upright_, 0.0, walls);
    ASSERT_TRUE(descriptor_.Compute(View(f0), level_).ok());
    const std::vector<std::uint8_t> place = DrawCanyon(upright_, 0.0, other_walls);
    std::vector<float> other(32);
    ASSERT_TRUE(descriptor_.Compute(View(place), other).ok());
    other_place_ = RelativeL2(level_, other);
  }
  double other_place() const { return other_place_; }
  // The change at a tilt; *unaware: the same frame described as if level.
  void Tilted(double roll, double pitch, double* change, double* unaware) {
    // Drawn with mount body = Ry(pitch) Rx(roll) * camera (dsp::Lens): in imu.h's convention
    // (body-to-world Ry(-pitch) Rx(roll)) that is a pitch of -pitch.
    drawn_.roll_deg = roll;
    drawn_.pitch_deg = pitch;
    Lens tilted_lens;
    ASSERT_EQ(tilted_lens.Init(drawn_), LensError::kOk);
    const std::vector<std::uint8_t> f = DrawCanyon(tilted_lens, 0.0, walls_);
    const Attitude attitude = AttitudeFromRollPitch(0, roll, -pitch);
    std::vector<float> tilted(32), level_assumed(32);
    ASSERT_TRUE(descriptor_.Compute(View(f), tilted, nullptr, &attitude).ok());
    ASSERT_TRUE(descriptor_.Compute(View(f), level_assumed).ok());
    *change = RelativeL2(level_, tilted);
    *unaware = RelativeL2(level_, level_assumed);
  }

 private:
  static ImageView View(const std::vector<std::uint8_t>& f) {
    return {f.data(), 480, 480, 480, PixelFormat::kGrey8};
  }
  LensParams drawn_;
  Lens upright_;
  SkyDescriptor descriptor_;
  std::vector<float> level_ = std::vector<float>(32);
  double walls_ = 1.0;
  double other_place_ = 0.0;
};

// The gravity-aligned cap with the true zenith: the camera tilts (drawn through a lens whose
// mount rotation is the tilt, so the pixels see a tilted sky) and the descriptor is told the
// zenith. The cap above 60 degrees is in view at every tilt up to 60 (185 degree lens), so
// its spectrum stays what it is level, to within the grid's aliasing of the mask edge.
TEST(SkyDescriptor, GravityCapIsTheSameAtAnyTiltUpToItsLimit) {
  CapAgainstAnotherPlace measure;
  ASSERT_NO_FATAL_FAILURE(measure.Init(CapElevationForTilt(60, 185), 4.0, 8.0));
  std::printf("  cap: different place: relative L2 %.4f\n", measure.other_place());
  for (const auto& [roll, pitch] : {std::pair{0.0, 10.0},
                                    {0.0, 30.0},
                                    {0.0, 60.0},
                                    {-25.0, 0.0},
                                    {40.0, -35.0},
                                    {-42.0, 42.0}}) {
    double change = 0, unaware = 0;
    ASSERT_NO_FATAL_FAILURE(measure.Tilted(roll, pitch, &change, &unaware));
    std::printf("  cap: roll %+3.0f pitch %+3.0f: relative L2 %.4f (assumed level: %.4f)\n", roll,
                pitch, change, unaware);
    EXPECT_LT(change, measure.other_place() / 5);
  }
}

// A skyline scene (no overhangs): sky above the elevation h(azimuth); buildings 40 degrees
// high with four open gaps of 50 degrees (one on each axis) down to 3 degrees.
bool GapsSky(const Eigen::Vector3d& d) {
  const double azimuth = std::atan2(d(1), d(0));
  const double to_axis = std::fabs(std::remainder(azimuth, std::numbers::pi / 2));
  const double skyline = to_axis < 25 * kDeg ? 3 * kDeg : 40 * kDeg;
  return d(2) > std::sin(skyline);
}

// Beyond its tilt limit the cap reaches below the field of view on the side the camera
// tilts away from. The skyline fill gives each such direction the value of the nearest seen
// one above it on its meridian: exact wherever the skyline is above the view's edge or
// below the unseen band, as everywhere in this scene (a gap's sky goes on down to 3 degrees,
// a building's top is above the edge). Without the fill the gaps read as ground. Reference:
// the analytic sky of every world-grid direction above the 10 degree cap, and which of them
// the tilted camera sees (its own lens, not the table); a sample (bilinear, 0..1) is right
// when it rounds to the truth. Pure pitch or roll, so the smallest
// rotation to the zenith is the camera's own (no yaw between the grids).
TEST(SkyDescriptor, SkylineFillRecoversTheCapBeyondTheTiltLimit) {
  LensParams drawn = TiltDrawingLens();
  Lens upright;
  ASSERT_EQ(upright.Init(drawn), LensError::kOk);
  ShGrid grid;
  ASSERT_EQ(grid.Init(DefaultShGridConfig(64)), ShError::kOk);
  SampleLut lut;
  ASSERT_EQ(lut.InitOriented(upright, grid, SampleLutOptions{}), SampleLutError::kOk);
  const double cap_sin = std::sin(10 * kDeg);
  for (const auto& [roll, pitch] : {std::pair{0.0, 25.0}, {0.0, -35.0}, {30.0, 0.0}, {0.0, 0.0}}) {
    drawn.roll_deg = roll;
    drawn.pitch_deg = pitch;
    Lens tilted_lens;
    ASSERT_EQ(tilted_lens.Init(drawn), LensError::kOk);
    const std::vector<std::uint8_t> f = DrawSky(tilted_lens, GapsSky);
    lut.Orient(AttitudeFromRollPitch(0, roll, -pitch).up);
    std::vector<float> raw(grid.sample_count());
    ASSERT_EQ(lut.SampleImage({f.data(), 480, 480, 480, PixelFormat::kGrey8}, 125, raw),
              SampleLutError::kOk);
    std::vector<float> filled = raw;
    lut.FillUnseenFromAbove(filled);
    int seen = 0, seen_right = 0, unseen = 0, unseen_sky = 0, filled_right = 0, raw_right = 0;
    for (std::size_t s = 0; s < grid.sample_count(); ++s) {
      const ShDirection d = grid.direction(s);
      if (d.z <= cap_sin)
        continue;
      const Eigen::Vector3d w(d.x, d.y, d.z);
      const float truth = GapsSky(w) ? 1.0f : 0.0f;
      double px = 0, py = 0;
      if (tilted_lens.RayToPixel(w, &px, &py)) {
        ++seen;
        seen_right += std::fabs(filled[s] - truth) < 0.5f ? 1 : 0;
        continue;
      }
      ++unseen;
      unseen_sky += truth == 1.0f ? 1 : 0;
      filled_right += std::fabs(filled[s] - truth) < 0.5f ? 1 : 0;
      raw_right += std::fabs(raw[s] - truth) < 0.5f ? 1 : 0;
    }
    std::printf(
        "  roll %+3.0f pitch %+3.0f: seen %d (%.2f %% right); unseen %d (%d sky): filled %d "
        "right, unfilled %d\n",
        roll, pitch, seen, 100.0 * seen_right / seen, unseen, unseen_sky, filled_right, raw_right);
    EXPECT_GT(seen_right, 0.99 * seen);
    if (roll == 0.0 && pitch == 0.0) {
      EXPECT_EQ(unseen, 0);  // level, the 185 degree lens sees the whole cap
      continue;
    }
    ASSERT_GT(unseen_sky, 20);  // a gap is hidden, or the test shows nothing
    EXPECT_GE(filled_right, unseen - 2);
    // Unfilled, the hidden gaps read as ground (2 to spare for a table cell at the rim that
    // the lens itself counts as unseen).
    EXPECT_LE(raw_right, unseen - unseen_sky + 2);
  }
}

// The street canyon has skylines that fall through the unseen band (the walls recede to
// the horizon towards the street's ends), where the fill is a guess. On the descriptor, at
// a 10 degree cap and tilts to 35, the cap's spectrum still stays much closer to the level
// one than another place (without the fill: 0.034 at 25 degrees and 0.071 at 35, against
// another place's 0.25).
TEST(SkyDescriptor, GravityCapBeyondItsLimitStaysCloserThanAnotherPlace) {
  CapAgainstAnotherPlace measure;
  ASSERT_NO_FATAL_FAILURE(measure.Init(10.0, 1.0, 1.6));
  std::printf("  cap 10: different place: relative L2 %.4f\n", measure.other_place());
  for (const double pitch : {15.0, 25.0, 35.0}) {
    double change = 0, unaware = 0;
    ASSERT_NO_FATAL_FAILURE(measure.Tilted(0.0, pitch, &change, &unaware));
    std::printf("  cap 10: pitch %+3.0f: relative L2 %.4f\n", pitch, change);
    EXPECT_LT(change, measure.other_place() / 5);
  }
}

// Without the cap (no attitude source) the descriptor is the one of every earlier version:
// an attitude passed in is ignored bit for bit, and the cap's options are not even checked.
TEST(SkyDescriptor, WithoutTheCapAnAttitudeChangesNothing) {
  const Lens lens = FisheyeLens(240, 240);
  SkyDescriptorOptions options;
  options.bands = 32;
  options.cap = {false, 200.0, -5.0};  // nonsense, but off
  SkyDescriptor descriptor;
  ASSERT_TRUE(descriptor.Init(lens, options).ok());
  const std::vector<std::uint8_t> f = DrawCanyon(lens, 0.3);
  const ImageView view{f.data(), 240, 240, 240, PixelFormat::kGrey8};
  std::vector<float> plain(32), with_attitude(32);
  ASSERT_TRUE(descriptor.Compute(view, plain).ok());
  const Attitude tilted = AttitudeFromRollPitch(0, 30.0, -20.0);
  ASSERT_TRUE(descriptor.Compute(view, with_attitude, nullptr, &tilted).ok());
  EXPECT_EQ(plain, with_attitude);
  // And the cap on changes it (so the comparison above can fail).
  options.cap = {true, 30.0, 10.0};
  SkyDescriptor capped;
  ASSERT_TRUE(capped.Init(lens, options).ok());
  ASSERT_TRUE(capped.Compute(view, with_attitude, nullptr, &tilted).ok());
  EXPECT_NE(plain, with_attitude);
  // A cap outside its range is refused at Init, naming it.
  options.cap = {true, 85.0, 10.0};
  const DescriptorError e = capped.Init(lens, options);
  EXPECT_FALSE(e.ok());
  EXPECT_NE(std::string(e.message).find("gravity cap"), std::string::npos) << e.message;
}

TEST(SkyDescriptor, DirectAndViaMaskPathsGiveTheSameDescriptor) {
  const Lens lens = FisheyeLens(320, 240);
  const std::vector<std::uint8_t> frame = DrawCanyon(lens, 0.3);
  const ImageView image{frame.data(), 320, 240, 320, PixelFormat::kGrey8};
  SkyDescriptorOptions options;
  options.bands = 24;
  SkyDescriptor direct, via_mask;
  ASSERT_TRUE(direct.Init(lens, options).ok());
  options.path = SamplingPath::kViaMask;
  ASSERT_TRUE(via_mask.Init(lens, options).ok());
  std::vector<float> a(24), b(24);
  ASSERT_TRUE(direct.Compute(image, a).ok());
  ASSERT_TRUE(via_mask.Compute(image, b).ok());
  EXPECT_EQ(a, b);
  EXPECT_TRUE(direct.mask().empty());
  ASSERT_FALSE(via_mask.mask().empty());
  EXPECT_EQ(via_mask.mask().Row(120)[160], kMaskSky);  // the zenith is open sky
}

TEST(SkyDescriptor, PaperGridAndErrors) {
  const Lens lens = FisheyeLens(200, 200);
  SkyDescriptorOptions options;
  options.grid = PaperShGridConfig();
  SkyDescriptor descriptor;
  ASSERT_TRUE(descriptor.Init(lens, options).ok());
  const ShGridConfig paper = PaperShGridConfig();
  EXPECT_EQ(descriptor.lut().size(),
            static_cast<std::size_t>(paper.rings) * static_cast<std::size_t>(paper.longitudes));
  EXPECT_NEAR(static_cast<double>(descriptor.lut().size()), 2000.0, 100.0);  // the paper's ~2000
  EXPECT_EQ(descriptor.bands(), 120);
  std::vector<std::uint8_t> frame(200 * 200, 100);
  std::vector<float> a(119);
  DescriptorError e = descriptor.Compute({frame.data(), 200, 200, 200, PixelFormat::kGrey8}, a);
  EXPECT_EQ(e.stage, DescriptorError::Stage::kProjection);
  a.resize(120);
  e = descriptor.Compute({frame.data(), 199, 200, 200, PixelFormat::kGrey8}, a);
  EXPECT_EQ(e.stage, DescriptorError::Stage::kSegmentation);
  EXPECT_NE(std::string(e.message).find("size"), std::string::npos);
  options.bands = 0;
  EXPECT_EQ(descriptor.Init(lens, options).stage, DescriptorError::Stage::kGrid);
}

TEST(SkyDescriptor, ComputeAllocatesNothingOverManyFrames) {
  ASSERT_TRUE(AllocationCounterActive());
  const Lens lens = FisheyeLens(320, 240);
  std::vector<std::vector<std::uint8_t>> frames;
  for (int i = 0; i < 4; ++i)
    frames.push_back(DrawCanyon(lens, i * 0.4));
  for (SamplingPath path : {SamplingPath::kDirect, SamplingPath::kViaMask}) {
    SkyDescriptorOptions options;
    options.bands = 64;
    options.path = path;
    options.sampling.footprint = 3;
    SkyDescriptor descriptor;
    ASSERT_TRUE(descriptor.Init(lens, options).ok());
    std::vector<float> amplitudes(64);
    SegmentationResult r;
    AllocationScope scope;
    for (int i = 0; i < 100; ++i) {
      const auto& f = frames[static_cast<std::size_t>(i % 4)];
      ASSERT_TRUE(
          descriptor.Compute({f.data(), 320, 240, 320, PixelFormat::kGrey8}, amplitudes, &r).ok());
    }
    EXPECT_EQ(scope.allocations(), 0u);
  }
}

}  // namespace
}  // namespace skyloc::dsp
