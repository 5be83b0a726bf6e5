#include "tools/surf1d_experiment.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "skyloc/sim/renderer.h"

namespace skyloc::tools {
namespace {

using sim::Material;
using sim::Renderer;
using sim::Texture;
using sim::World;

constexpr double kDegToRad = std::numbers::pi / 180.0;

// The forward pinhole camera of the 1D SURF experiment, smaller.
dsp::LensParams ForwardPinhole(int width, int height, double fov_deg) {
  dsp::LensParams p;
  p.model = dsp::LensModel::kPinhole;
  p.width = width;
  p.height = height;
  p.fov_deg = fov_deg;
  p.roll_deg = -90.0;
  p.yaw_deg = -90.0;
  return p;
}

// First row of column x that the ground hides (the sky mask reads 0), or height.
int FirstGroundRow(const std::vector<std::uint8_t>& mask, int width, int height, int x) {
  for (int y = 0; y < height; ++y)
    if (mask[static_cast<std::size_t>(y * width + x)] == 0)
      return y;
  return height;
}

// In an empty world the horizon of a forward perspective camera pitched by p (nose up) is
// the row cy + f tan(p), f = (W / 2) / tan(fov / 2), across the whole image: the textbook
// projection, against the renderer's sky mask (its own rays through dsp::Lens, the mount
// and the pose) and against PinholeHorizonRow.
TEST(PinholeRenderer, ForwardCameraHorizonIsTheAnalyticRow) {
  // Nothing above the ground: one small triangle far below it (a world needs one).
  World world;
  const Material m{0.5f, 0.5f, 0.5f, 0.03f, Texture::kPlain};
  world.AddTriangle({0, 0, -50}, {1, 0, -50}, {0, 1, -50}, m);
  ASSERT_TRUE(world.Finish().ok());
  constexpr int kW = 320, kH = 240;
  Renderer renderer;
  ASSERT_TRUE(renderer.Init(&world, ForwardPinhole(kW, kH, 47.8)).ok());
  const double f = kW / 2.0 / std::tan(23.9 * kDegToRad);
  std::vector<std::uint8_t> mask(kW * kH);
  const dsp::MutableImageView view{mask.data(), kW, kH, kW, dsp::PixelFormat::kGrey8};
  for (double pitch : {0.0, 6.0, -9.0}) {
    const drivers::Pose pose{3, -2, 1.0, 0, pitch, 71};  // yaw must not matter
    ASSERT_TRUE(renderer.RenderSkyMask(pose, view).ok());
    const double row = (kH - 1) / 2.0 + f * std::tan(pitch * kDegToRad);
    for (int x = 0; x < kW; x += 7) {
      double computed = 0;
      ASSERT_TRUE(PinholeHorizonRow(renderer.lens(), pose, x, &computed));
      EXPECT_NEAR(computed, row, 1e-4) << "pitch " << pitch << " column " << x;
      // Pixel centres at or below the horizon see ground.
      EXPECT_NEAR(FirstGroundRow(mask, kW, kH, x), std::ceil(row), 1) << "pitch " << pitch;
    }
  }
  // Rolled: the horizon is a slanted line; the mask and PinholeHorizonRow agree on it.
  const drivers::Pose rolled{0, 0, 1.0, 12, -4, 0};
  ASSERT_TRUE(renderer.RenderSkyMask(rolled, view).ok());
  double left = 0, right = 0;
  ASSERT_TRUE(PinholeHorizonRow(renderer.lens(), rolled, 0, &left));
  ASSERT_TRUE(PinholeHorizonRow(renderer.lens(), rolled, kW - 1, &right));
  EXPECT_GT(std::fabs(right - left), 20.0);  // 12 degrees of roll tilt the line visibly
  for (int x = 0; x < kW; x += 7) {
    double computed = 0;
    ASSERT_TRUE(PinholeHorizonRow(renderer.lens(), rolled, x, &computed));
    EXPECT_NEAR(FirstGroundRow(mask, kW, kH, x), std::ceil(computed), 1) << "column " << x;
  }
  // Pitched so far down the horizon leaves the image: no row.
  double none = 0;
  EXPECT_FALSE(PinholeHorizonRow(renderer.lens(), {0, 0, 1, 0, -40, 0}, 100, &none));
}

}  // namespace
}  // namespace skyloc::tools
