// 1D SURF on rendered views of a procedural city (the simulator's ray-traced fisheye
// frames, visible light, with sun, clouds and sensor noise): heading recovery between two
// yaws at one place, and place recognition along the route (the paper's classification
// experiment, with "same place" = same route point, different yaw and lighting).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "skyloc/dsp/horizon_strip.h"
#include "skyloc/dsp/surf1d.h"
#include "skyloc/sim/renderer.h"
#include "skyloc/sim/world.h"

namespace skyloc::sim {
namespace {

constexpr int kSize = 320;

class Surf1dSimTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(MakeProceduralWorld(WorldKind::kCity, 7, &world_).ok());
    ASSERT_GE(world_.route.size(), 2u);
    ASSERT_TRUE(renderer_.Init(&world_, DefaultSimLens(kSize, kSize)).ok());
    ASSERT_EQ(strip_.Init(renderer_.lens(), dsp::HorizonStripOptions{}),
              dsp::HorizonStripError::kOk);
    ASSERT_EQ(surf_.Init(strip_.n_azimuth(), dsp::Surf1dOptions{}), dsp::Surf1dError::kOk);
    ASSERT_EQ(matcher_.Init(512, dsp::LandmarkMatchOptions{}), dsp::Surf1dError::kOk);
    image_.assign(static_cast<std::size_t>(kSize * kSize * 3), 0);
    values_.assign(static_cast<std::size_t>(strip_.n_azimuth()), 0.0f);
  }

  // The point `s` metres along the route (straight segments).
  drivers::Pose At(double s) const {
    for (std::size_t i = 0; i + 1 < world_.route.size(); ++i) {
      const Point2 a = world_.route[i], b = world_.route[i + 1];
      const double len = std::hypot(b.x - a.x, b.y - a.y);
      if (s <= len || i + 2 == world_.route.size()) {
        const double t = len > 0 ? std::min(s / len, 1.0) : 0.0;
        drivers::Pose p;
        p.x_m = a.x + t * (b.x - a.x);
        p.y_m = a.y + t * (b.y - a.y);
        p.z_m = 0.1;
        return p;
      }
      s -= len;
    }
    return {};
  }

  double RouteLength() const {
    double total = 0;
    for (std::size_t i = 0; i + 1 < world_.route.size(); ++i)
      total += std::hypot(world_.route[i + 1].x - world_.route[i].x,
                          world_.route[i + 1].y - world_.route[i].y);
    return total;
  }

  std::vector<dsp::Surf1dFeature> Features(const drivers::Pose& pose, const Lighting& lighting,
                                           std::uint64_t frame_seed) {
    const dsp::MutableImageView view{image_.data(), kSize, kSize,
                                     static_cast<std::size_t>(kSize * 3), dsp::PixelFormat::kRgb24};
    EXPECT_TRUE(renderer_.Render(pose, lighting, Spectrum::kVisible, frame_seed, view).ok());
    EXPECT_EQ(strip_.Extract(view, values_), dsp::HorizonStripError::kOk);
    std::vector<dsp::Surf1dFeature> f(512);
    int count = 0;
    EXPECT_EQ(surf_.Detect(values_, f, &count), dsp::Surf1dError::kOk);
    f.resize(static_cast<std::size_t>(count));
    return f;
  }

  World world_;
  Renderer renderer_;
  dsp::HorizonStrip strip_;
  dsp::Surf1d surf_;
  dsp::LandmarkMatcher matcher_;
  std::vector<std::uint8_t> image_;
  std::vector<float> values_;
};

double WrapDegrees(double d) {
  return d - 360.0 * std::round(d / 360.0);
}

// The renderer's camera has image right = body left, a proper rotation of the body frame,
// so a robot that turns by +psi (counter-clockwise) sees its scene turned by -psi.
TEST_F(Surf1dSimTest, RecoversTheRobotsTurnAtOnePlace) {
  Lighting lighting;
  const double length = RouteLength();
  for (const double s : {0.2 * length, 0.6 * length}) {
    drivers::Pose pose = At(s);
    const std::vector<dsp::Surf1dFeature> stored = Features(pose, lighting, 1);
    for (const double turn : {35.0, -110.0, 172.0}) {
      drivers::Pose turned = pose;
      turned.yaw_deg = turn;
      const std::vector<dsp::Surf1dFeature> test = Features(turned, lighting, 2);
      dsp::LandmarkMatch m;
      ASSERT_EQ(matcher_.Match(stored, test, strip_.n_azimuth(), &m), dsp::Surf1dError::kOk);
      ASSERT_TRUE(m.model_found) << "s=" << s << " turn=" << turn;
      EXPECT_LE(std::abs(WrapDegrees(m.heading_offset_deg + turn)), 2.0)
          << "s=" << s << " turn=" << turn << " recovered " << m.heading_offset_deg;
      std::printf("route %.1f m, turn %+6.1f deg: offset %+7.2f deg, %d matches, %d inliers\n", s,
                  turn, m.heading_offset_deg, m.matches, m.inliers);
    }
  }
}

double Auc(const std::vector<double>& positives, const std::vector<double>& negatives) {
  double wins = 0.0;
  for (const double a : positives)
    for (const double b : negatives)
      wins += a > b ? 1.0 : (a == b ? 0.5 : 0.0);
  return wins / (static_cast<double>(positives.size()) * static_cast<double>(negatives.size()));
}

// Stored: route points at noon-ish light, yaw 0. Test: the same points turned by a yaw
// that varies, with another sun, clouds and noise. Pairs of different points more than
// 10 m apart are the unmatched ones.
TEST_F(Surf1dSimTest, PlacesAlongTheRouteAreRecognised) {
  const double length = RouteLength();
  const int places = 12;
  Lighting stored_light;
  Lighting test_light;
  test_light.sun_azimuth_deg = 250;
  test_light.sun_elevation_deg = 30;
  test_light.cloud_cover = 0.4;
  test_light.exposure_ev = -0.5;
  test_light.seed = 9;
  std::vector<std::vector<dsp::Surf1dFeature>> stored, test;
  std::vector<double> where;
  for (int i = 0; i < places; ++i) {
    const double s = (i + 0.5) * length / places;
    where.push_back(s);
    drivers::Pose pose = At(s);
    stored.push_back(Features(pose, stored_light, 10u + static_cast<unsigned>(i)));
    pose.yaw_deg = -170.0 + 29.0 * i;
    test.push_back(Features(pose, test_light, 50u + static_cast<unsigned>(i)));
  }
  std::vector<double> pos, neg;
  int heading_ok = 0;
  for (int a = 0; a < places; ++a) {
    for (int b = 0; b < places; ++b) {
      if (a != b &&
          std::abs(where[static_cast<std::size_t>(a)] - where[static_cast<std::size_t>(b)]) < 10.0)
        continue;
      dsp::LandmarkMatch m;
      ASSERT_EQ(matcher_.Match(stored[static_cast<std::size_t>(a)],
                               test[static_cast<std::size_t>(b)], strip_.n_azimuth(), &m),
                dsp::Surf1dError::kOk);
      const double score = m.model_found ? m.ransac_score : 0.0;
      (a == b ? pos : neg).push_back(score);
      if (a == b && m.model_found &&
          std::abs(WrapDegrees(m.heading_offset_deg - (170.0 - 29.0 * a))) <= 2.0)
        ++heading_ok;
    }
  }
  ASSERT_FALSE(neg.empty());
  const double auc = Auc(pos, neg);
  std::printf(
      "1D SURF, city route %.0f m, %d places: AUC (NN with RANSAC) %.3f over %zu matched "
      "/ %zu unmatched pairs; heading within 2 deg at %d/%d places\n",
      length, places, auc, pos.size(), neg.size(), heading_ok, places);
  RecordProperty("auc_ransac", std::to_string(auc));
  EXPECT_GE(auc, 0.9);
  EXPECT_GE(heading_ok, places * 3 / 4);
}

}  // namespace
}  // namespace skyloc::sim
