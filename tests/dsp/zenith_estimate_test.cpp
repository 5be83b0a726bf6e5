#include "skyloc/dsp/zenith_estimate.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <utility>
#include <vector>

#include "skyloc/dsp/sky_descriptor.h"
#include "skyloc/platform/alloc_counter.h"
#include "support/angles.h"

namespace skyloc::dsp {
namespace {

constexpr int kSize = 480;

// Open terrain: sky above a flat horizon at `horizon_deg` of elevation, all round.
bool OpenSky(const Eigen::Vector3d& d, double horizon_deg) {
  return d(2) > std::sin(horizon_deg * kDeg);
}

// A street canyon along x, walls of different heights on each side (height over distance
// 1.3 on +y, 0.8 on -y), as tests/dsp/sky_descriptor_test.cpp's.
bool CanyonSky(const Eigen::Vector3d& d) {
  if (d(2) <= 0.0)
    return false;
  const double wall = d(1) > 0 ? 1.3 : 0.8;
  return std::fabs(d(1)) * wall <= d(2);
}

// The scene drawn through a lens whose mount rotation is the tilt (the pixels see a tilted
// sky; see sky_descriptor_test.cpp, GravityCapIsTheSameAtAnyTiltUpToItsLimit).
template <typename Sky>
std::vector<std::uint8_t> Draw(double roll_deg, double pitch_deg, Sky sky) {
  LensParams p;
  p.width = p.height = kSize;
  p.fov_deg = 185.0;
  p.roll_deg = roll_deg;
  p.pitch_deg = pitch_deg;
  Lens lens;
  EXPECT_EQ(lens.Init(p), LensError::kOk);
  std::vector<std::uint8_t> grey(static_cast<std::size_t>(kSize * kSize));
  Eigen::Vector3d ray;
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x)
      grey[static_cast<std::size_t>(y * kSize + x)] =
          lens.PixelToRay(x, y, &ray) ? (sky(ray) ? 210 : 40) : 5;
  return grey;
}

// The sky descriptor's samples of the frame (the product's grid: 120 bands).
class Fixture {
 public:
  explicit Fixture(ZenithEstimateOptions options = {}) {
    LensParams p;
    p.width = p.height = kSize;
    p.fov_deg = 185.0;
    EXPECT_EQ(lens_.Init(p), LensError::kOk);
    SkyDescriptorOptions o;
    o.bands = 120;
    EXPECT_TRUE(descriptor_.Init(lens_, o).ok());
    EXPECT_TRUE(estimator_.Init(descriptor_.grid(), options));
    amplitudes_.resize(120);
  }
  // The angle between the estimated zenith and the true one (degrees); < 0: no estimate.
  double Error(const std::vector<std::uint8_t>& frame, double roll_deg, double pitch_deg,
               Attitude* estimate = nullptr) {
    EXPECT_TRUE(
        descriptor_.Compute({frame.data(), kSize, kSize, kSize, PixelFormat::kGrey8}, amplitudes_)
            .ok());
    Attitude a;
    if (!estimator_.Estimate(descriptor_.samples(), 0, &a))
      return -1;
    if (estimate != nullptr)
      *estimate = a;
    // Drawn with mount body = Ry(pitch) Rx(roll) * camera: imu.h's pitch is -pitch.
    const Attitude truth = AttitudeFromRollPitch(0, roll_deg, -pitch_deg);
    const double c = a.up[0] * truth.up[0] + a.up[1] * truth.up[1] + a.up[2] * truth.up[2];
    return std::acos(std::min(1.0, c)) / kDeg;
  }
  SkyDescriptor& descriptor() { return descriptor_; }
  ZenithEstimator& estimator() { return estimator_; }

 private:
  Lens lens_;
  SkyDescriptor descriptor_;
  ZenithEstimator estimator_;
  std::vector<float> amplitudes_;
};

const std::pair<double, double> kTilts[] = {{0, 0},    {0, 10},   {0, 30}, {-25, 0},
                                            {20, -20}, {-30, 30}, {0, 45}, {40, -35}};

double TiltOf(double roll, double pitch) {
  return std::acos(std::cos(roll * kDeg) * std::cos(pitch * kDeg)) / kDeg;
}

// Open terrain: the skyline is the horizon, a small circle about the zenith; its mean plane
// is the horizontal, however much of it the tilted lens crops (measured: under 0.2 degrees
// at tilts to 51 degrees on the 120-band grid).
TEST(ZenithEstimate, SkylinePlaneFindsTheTiltOfAnOpenHorizon) {
  Fixture f;
  for (double horizon : {5.0, 10.0, 25.0}) {
    for (const auto& [roll, pitch] : kTilts) {
      const auto frame =
          Draw(roll, pitch, [horizon](const auto& d) { return OpenSky(d, horizon); });
      Attitude a;
      const double error = f.Error(frame, roll, pitch, &a);
      std::printf("  horizon %2.0f, roll %+3.0f pitch %+3.0f (tilt %2.0f): error %.2f deg\n",
                  horizon, roll, pitch, TiltOf(roll, pitch), error);
      EXPECT_GE(error, 0.0);
      EXPECT_LT(error, 0.5);
      EXPECT_NEAR(a.roll_deg, roll, 0.7);
      EXPECT_NEAR(a.pitch_deg, -pitch, 0.7);
    }
  }
}

// The sky centroid on the same open horizon: exact when level, biased towards the lens's
// axis when tilted (the grid's edge crops the sky on the low side) - a few degrees per ten.
TEST(ZenithEstimate, SkyCentroidIsBiasedTowardsTheLensAxisWhenTilted) {
  ZenithEstimateOptions o;
  o.method = ZenithMethod::kSkyCentroid;
  Fixture f(o);
  const auto level = Draw(0, 0, [](const auto& d) { return OpenSky(d, 10); });
  EXPECT_LT(f.Error(level, 0, 0), 0.5);
  const auto tilted = Draw(0, 30, [](const auto& d) { return OpenSky(d, 10); });
  Attitude a;
  const double error = f.Error(tilted, 0, 30, &a);
  std::printf("  centroid, open horizon 10, pitch 30: error %.2f deg (estimated tilt %.1f)\n",
              error, -a.pitch_deg);
  EXPECT_GT(error, 1.0);
  EXPECT_LT(-a.pitch_deg, 30.0);  // under-estimated: pulled towards the lens's axis
}

// An asymmetric street canyon (walls 1.3 and 0.8 high over their distance): both roof lines
// are great circles through the camera, at different elevations, so their mean plane leans
// towards the higher wall even when the camera is level. This is the bias of the method in
// a built-up place; it does not depend much on the tilt.
TEST(ZenithEstimate, SkylinePlaneLeansInAnAsymmetricCanyon) {
  Fixture f;
  for (const auto& [roll, pitch] : {std::pair{0.0, 0.0}, {0.0, 20.0}, {15.0, 0.0}}) {
    const auto frame = Draw(roll, pitch, [](const auto& d) { return CanyonSky(d); });
    Attitude a;
    const double error = f.Error(frame, roll, pitch, &a);
    std::printf("  canyon, roll %+3.0f pitch %+3.0f: error %.2f deg (roll %+.1f pitch %+.1f)\n",
                roll, pitch, error, a.roll_deg, a.pitch_deg);
    EXPECT_GT(error, 3.0);
    EXPECT_LT(error, 20.0);
  }
}

TEST(ZenithEstimate, NoSkylineNoEstimate) {
  Fixture f;
  const auto all_sky = Draw(0, 0, [](const auto&) { return true; });
  EXPECT_LT(f.Error(all_sky, 0, 0), 0.0);
  // A level camera under a horizon at 0 degrees: the skyline is the grid's edge, not in it.
  const auto horizon_at_edge = Draw(0, 0, [](const auto& d) { return OpenSky(d, 0); });
  EXPECT_LT(f.Error(horizon_at_edge, 0, 0), 0.0);
  const auto no_sky = Draw(0, 0, [](const auto&) { return false; });
  EXPECT_LT(f.Error(no_sky, 0, 0), 0.0);
  ZenithEstimator unset;
  Attitude a;
  EXPECT_FALSE(unset.Estimate(f.descriptor().samples(), 0, &a));
  ZenithEstimateOptions bad;
  bad.iterations = 0;
  EXPECT_FALSE(unset.Init(f.descriptor().grid(), bad));
}

TEST(ZenithEstimate, EstimateAllocatesNothing) {
  ASSERT_TRUE(AllocationCounterActive());
  for (ZenithMethod method : {ZenithMethod::kSkylinePlane, ZenithMethod::kSkyCentroid}) {
    ZenithEstimateOptions o;
    o.method = method;
    Fixture f(o);
    const auto frame = Draw(10, 10, [](const auto& d) { return OpenSky(d, 5); });
    f.Error(frame, 10, 10);
    Attitude a;
    AllocationScope scope;
    for (int i = 0; i < 20; ++i)
      ASSERT_TRUE(f.estimator().Estimate(f.descriptor().samples(), i, &a));
    EXPECT_EQ(scope.allocations(), 0u);
  }
}

}  // namespace
}  // namespace skyloc::dsp
