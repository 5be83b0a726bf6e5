#include "skyloc/sim/renderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "skyloc/dsp/otsu.h"
#include "support/angles.h"

namespace skyloc::sim {
namespace {

// Lighting with nothing random in it: no clouds, noise or flare.
Lighting PlainLighting() {
  Lighting l;
  l.cloud_cover = 0;
  l.noise_sigma = 0;
  l.flare = 0;
  l.sun_elevation_deg = 50;
  return l;
}

struct Image {
  Image(int w, int h, dsp::PixelFormat f)
      : bytes(static_cast<std::size_t>(w * h * (f == dsp::PixelFormat::kGrey8 ? 1 : 3))),
        view{bytes.data(), w, h,
             static_cast<std::size_t>(w * (f == dsp::PixelFormat::kGrey8 ? 1 : 3)), f} {}
  std::uint8_t at(int x, int y) const { return view.Row(y)[x]; }
  std::vector<std::uint8_t> bytes;
  dsp::MutableImageView view;
};

// An open vertical tube (no lid) of radius R around the origin, wall top at `top` m.
void AddTube(World& w, double radius, double top, int segments) {
  const Material m{0.5f, 0.5f, 0.5f, 0.03f, Texture::kPlain};
  for (int i = 0; i < segments; ++i) {
    const double a0 = 2 * kPi * i / segments, a1 = 2 * kPi * (i + 1) / segments;
    auto p = [&](double a, double z) {
      return Vec3{static_cast<float>(radius * std::cos(a)),
                  static_cast<float>(radius * std::sin(a)), static_cast<float>(z)};
    };
    w.AddQuad(p(a0, 0), p(a1, 0), p(a1, top), p(a0, top), m);
  }
}

int CountAbove(const Image& img, int threshold) {
  int n = 0;
  for (int y = 0; y < img.view.height; ++y) {
    for (int x = 0; x < img.view.width; ++x)
      n += img.at(x, y) > threshold ? 1 : 0;
  }
  return n;
}

// Focal length of the equidistant lens, pixels per radian.
double Focal(const Renderer& r) {
  return r.lens().radius_px() / r.lens().max_theta();
}

bool InCircle(const Renderer& r, int x, int y) {
  Eigen::Vector3d d;
  return r.lens().PixelToCameraRay(x, y, &d);
}

// Inside a tube of radius R whose rim is H above the camera, the sky is a disc of angular
// radius atan(R / H) about the zenith: radius f * atan(R / H) pixels in an equidistant lens.
TEST(Renderer, SkyDiscInsideATubeMatchesTheAnalyticRadius) {
  World world;
  AddTube(world, 10.0, 11.0, 720);
  ASSERT_TRUE(world.Finish().ok());
  Renderer renderer;
  ASSERT_TRUE(renderer.Init(&world, DefaultSimLens(240, 240)).ok());
  const drivers::Pose pose{0, 0, 1.0, 0, 0, 33};  // level; yaw must not matter
  Image mask(240, 240, dsp::PixelFormat::kGrey8);
  ASSERT_TRUE(renderer.RenderSkyMask(pose, mask.view).ok());
  Image uv(240, 240, dsp::PixelFormat::kGrey8);
  ASSERT_TRUE(renderer.Render(pose, PlainLighting(), Spectrum::kUv, 0, uv.view).ok());

  const double predicted_px = Focal(renderer) * std::atan2(10.0, 10.0);
  const double mask_px = std::sqrt(CountAbove(mask, 127) / kPi);
  const double uv_px = std::sqrt(CountAbove(uv, 128) / kPi);
  EXPECT_NEAR(mask_px, predicted_px, 1.0);
  EXPECT_NEAR(uv_px, predicted_px, 1.0);
  // Sky fraction of the image circle = (theta_sky / theta_max)^2.
  const double circle = kPi * 120.0 * 120.0;
  EXPECT_NEAR(CountAbove(mask, 127) / circle, std::pow(45.0 / 92.5, 2), 0.01);
}

// A long wall D metres ahead, H above the camera: its top is at elevation atan(H / D)
// straight ahead, i.e. theta = 90 - e + pitch from the optical axis.
class WallTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const Material m{0.5f, 0.5f, 0.5f, 0.03f, Texture::kPlain};
    world_.AddBox(20 + 1, 0, 0, 2, 400, 16, 0, m);  // front face at x = 20, top 16 m
    ASSERT_TRUE(world_.Finish().ok());
    ASSERT_TRUE(renderer_.Init(&world_, DefaultSimLens(300, 300)).ok());
  }
  // Sky pixels counted from the image centre outwards along (dx, dy) until the first
  // blocked one: the skyline's distance from the centre, to within a pixel.
  int SkyRun(const drivers::Pose& pose, int dx, int dy) {
    Image mask(300, 300, dsp::PixelFormat::kGrey8);
    EXPECT_TRUE(renderer_.RenderSkyMask(pose, mask.view).ok());
    int n = 0;
    // Start from the pixel whose centre is 0.5 px from the axis on the chosen side.
    int x = dx < 0 ? 149 : 150, y = dy < 0 ? 149 : 150;
    if (dx == 0)
      x = 150;
    if (dy == 0)
      y = 150;
    while (x >= 0 && y >= 0 && x < 300 && y < 300 && mask.at(x, y) == 255) {
      ++n;
      x += dx;
      y += dy;
    }
    return n;
  }
  double PredictedRadius(double elevation_rad, double pitch_deg) {
    return Focal(renderer_) * (kPi / 2 - elevation_rad + pitch_deg * kDeg);
  }
  World world_;
  Renderer renderer_;
};

TEST_F(WallTest, SkylineAheadIsAtTheAnalyticElevation) {
  const double e = std::atan2(16.0 - 1.0, 20.0);
  // Heading +x (yaw 0): the wall is ahead, at the top of the image.
  EXPECT_NEAR(SkyRun({0, 0, 1, 0, 0, 0}, 0, -1), PredictedRadius(e, 0), 1.0);
  // Behind there is no wall: sky down to the horizon, theta = 90 degrees.
  EXPECT_NEAR(SkyRun({0, 0, 1, 0, 0, 0}, 0, 1), PredictedRadius(0, 0), 1.0);
}

TEST_F(WallTest, YawMovesTheWallToTheRightSideOfTheImage) {
  const double e = std::atan2(15.0, 20.0);
  // Heading +y (yaw 90): the wall (+x) is on the robot's right, which an upward camera
  // shows on the image's left.
  EXPECT_NEAR(SkyRun({0, 0, 1, 0, 0, 90}, -1, 0), PredictedRadius(e, 0), 1.0);
  EXPECT_NEAR(SkyRun({0, 0, 1, 0, 0, 90}, 1, 0), PredictedRadius(0, 0), 1.0);
}

TEST_F(WallTest, NoseUpPitchPushesTheSkylineAheadOutwards) {
  const double e = std::atan2(15.0, 20.0);
  EXPECT_NEAR(SkyRun({0, 0, 1, 0, 20, 0}, 0, -1), PredictedRadius(e, 20), 1.0);
  // Nose down: the optical axis leans toward the wall.
  EXPECT_NEAR(SkyRun({0, 0, 1, 0, -20, 0}, 0, -1), PredictedRadius(e, -20), 1.0);
}

TEST(Renderer, SameSeedAndPoseGiveIdenticalBytes) {
  World world;
  ASSERT_TRUE(MakeProceduralWorld(WorldKind::kCity, 5, &world).ok());
  Renderer renderer;
  ASSERT_TRUE(renderer.Init(&world, DefaultSimLens(96, 64)).ok());
  const drivers::Pose pose{world.route[0].x + 3, world.route[0].y, 1.2, 3, -5, 20};
  Lighting lighting;
  ASSERT_TRUE(LightingPreset("dawn", 9, &lighting));
  for (Spectrum s : {Spectrum::kUv, Spectrum::kVisible}) {
    const auto f = s == Spectrum::kUv ? dsp::PixelFormat::kGrey8 : dsp::PixelFormat::kRgb24;
    Image a(96, 64, f), b(96, 64, f), c(96, 64, f);
    ASSERT_TRUE(renderer.Render(pose, lighting, s, 4, a.view).ok());
    ASSERT_TRUE(renderer.Render(pose, lighting, s, 4, b.view).ok());
    ASSERT_TRUE(renderer.Render(pose, lighting, s, 5, c.view).ok());
    EXPECT_EQ(a.bytes, b.bytes) << SpectrumName(s);
    EXPECT_NE(a.bytes, c.bytes) << "the frame seed must change the sensor noise";
  }
  // A second world from the same seed renders the same image too.
  World again;
  ASSERT_TRUE(MakeProceduralWorld(WorldKind::kCity, 5, &again).ok());
  Renderer renderer2;
  ASSERT_TRUE(renderer2.Init(&again, DefaultSimLens(96, 64)).ok());
  Image a(96, 64, dsp::PixelFormat::kGrey8), b(96, 64, dsp::PixelFormat::kGrey8);
  ASSERT_TRUE(renderer.Render(pose, lighting, Spectrum::kUv, 1, a.view).ok());
  ASSERT_TRUE(renderer2.Render(pose, lighting, Spectrum::kUv, 1, b.view).ok());
  EXPECT_EQ(a.bytes, b.bytes);
}

dsp::Histogram256 HistogramInCircle(const Image& img, const Renderer& r) {
  dsp::Histogram256 h{};
  for (int y = 0; y < img.view.height; ++y) {
    for (int x = 0; x < img.view.width; ++x) {
      if (InCircle(r, x, y))
        ++h[img.at(x, y)];
    }
  }
  return h;
}

// The UV image separates sky from everything else: Otsu's threshold reproduces the
// ground-truth sky mask almost everywhere (a clear day, sun out of view).
TEST(Renderer, OtsuOnTheUvImageRecoversTheSkyMask) {
  World world;
  ASSERT_TRUE(MakeProceduralWorld(WorldKind::kForest, 2, &world).ok());
  Renderer renderer;
  ASSERT_TRUE(renderer.Init(&world, DefaultSimLens(120, 120)).ok());
  Lighting lighting;
  ASSERT_TRUE(LightingPreset("noon", 1, &lighting));
  const drivers::Pose pose{world.route[40].x, world.route[40].y, 1.0, 0, 0, 0};
  Image uv(120, 120, dsp::PixelFormat::kGrey8), mask(120, 120, dsp::PixelFormat::kGrey8);
  ASSERT_TRUE(renderer.Render(pose, lighting, Spectrum::kUv, 0, uv.view).ok());
  ASSERT_TRUE(renderer.RenderSkyMask(pose, mask.view).ok());
  const int threshold = dsp::OtsuThreshold(HistogramInCircle(uv, renderer)).threshold;
  int agree = 0, total = 0, sky = 0;
  for (int y = 0; y < 120; ++y) {
    for (int x = 0; x < 120; ++x) {
      if (!InCircle(renderer, x, y))
        continue;
      ++total;
      sky += mask.at(x, y) == 255 ? 1 : 0;
      agree += (uv.at(x, y) > threshold) == (mask.at(x, y) == 255) ? 1 : 0;
    }
  }
  EXPECT_GT(sky, total / 20) << "the view should show some sky";
  EXPECT_LT(sky, total * 9 / 10) << "and some canopy";
  EXPECT_GT(agree, total * 97 / 100);
}

// The flare (sun in view, nothing blocking it) brightens pixels near the sun that are
// ground, which is what fools Otsu in the paper's failure case.
TEST(Renderer, FlareBrightensGroundNearTheSun) {
  World world;
  world.AddBox(-30, 0, 0, 2, 2, 0.5, 0, Material{});  // something to build a BVH from
  ASSERT_TRUE(world.Finish().ok());
  Renderer renderer;
  ASSERT_TRUE(renderer.Init(&world, DefaultSimLens(200, 200)).ok());
  Lighting lighting = PlainLighting();
  lighting.sun_azimuth_deg = 0;  // ahead
  lighting.sun_elevation_deg = 5;
  lighting.flare = 1;
  // Nose down 20 degrees: the horizon ahead is at theta = 70 degrees, the sun (elevation
  // 5) at theta = 65; look at the ground 3 degrees below the horizon.
  const drivers::Pose pose{0, 0, 1, 0, -20, 0};
  Image with(200, 200, dsp::PixelFormat::kGrey8), without(200, 200, dsp::PixelFormat::kGrey8);
  ASSERT_TRUE(renderer.Render(pose, lighting, Spectrum::kUv, 0, with.view).ok());
  lighting.flare = 0;
  ASSERT_TRUE(renderer.Render(pose, lighting, Spectrum::kUv, 0, without.view).ok());
  const int x = 100, y_ground = static_cast<int>(100 - Focal(renderer) * 73 * kDeg);
  EXPECT_LT(without.at(x, y_ground), 100);
  EXPECT_GT(with.at(x, y_ground), without.at(x, y_ground) + 60);
  EXPECT_GT(with.at(x, y_ground), 128);  // brighter than mid-grey: Otsu would call it sky
  // Far from the sun the flare is small.
  EXPECT_NEAR(with.at(100, 190), without.at(100, 190), 40);
}

TEST(Renderer, RejectsAMismatchedOutput) {
  World world;
  world.AddBox(0, 0, 0, 1, 1, 1, 0, Material{});
  ASSERT_TRUE(world.Finish().ok());
  Renderer renderer;
  ASSERT_TRUE(renderer.Init(&world, DefaultSimLens(64, 48)).ok());
  Image rgb(64, 48, dsp::PixelFormat::kRgb24);
  EXPECT_EQ(renderer.Render({}, Lighting{}, Spectrum::kUv, 0, rgb.view).code(),
            StatusCode::kInvalidArgument);
  Image small(32, 48, dsp::PixelFormat::kGrey8);
  EXPECT_EQ(renderer.RenderSkyMask({}, small.view).code(), StatusCode::kInvalidArgument);
  Renderer bad;
  EXPECT_EQ(bad.Init(&world, DefaultSimLens(4, 48)).code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace skyloc::sim
