#include "skyloc/sim/motion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

namespace skyloc::sim {
namespace {

const std::vector<Point2> kStraight = {{0, 0}, {100, 0}};

TEST(Motion, StraightRouteIsSampledAtTheFrameSpacing) {
  MotionConfig config;
  config.frame_spacing_m = 2.0;
  config.speed_jitter = 0;
  config.height_m = 0.3;
  std::vector<TrajectoryPoint> t;
  ASSERT_TRUE(BuildTrajectory(kStraight, false, config, &t).ok());
  ASSERT_EQ(t.size(), 51u);
  for (std::size_t i = 0; i < t.size(); ++i) {
    EXPECT_NEAR(t[i].pose.x_m, 2.0 * static_cast<double>(i), 1e-9);
    EXPECT_EQ(t[i].pose.y_m, 0);
    EXPECT_EQ(t[i].pose.z_m, 0.3);
    EXPECT_NEAR(t[i].pose.yaw_deg, 0, 1e-9);
    EXPECT_NEAR(t[i].time_s, 0.1 * static_cast<double>(i), 1e-12);
  }
}

TEST(Motion, SpeedJitterStaysWithinItsBoundsAndVaries) {
  MotionConfig config;
  config.frame_spacing_m = 1.0;
  config.speed_jitter = 0.2;
  std::vector<TrajectoryPoint> t;
  ASSERT_TRUE(BuildTrajectory(kStraight, false, config, &t).ok());
  double lo = 10, hi = 0;
  for (std::size_t i = 1; i < t.size(); ++i) {
    const double step = t[i].route_m - t[i - 1].route_m;
    lo = std::min(lo, step);
    hi = std::max(hi, step);
  }
  EXPECT_GE(lo, 0.8 - 1e-9);
  EXPECT_LE(hi, 1.2 + 1e-9);
  EXPECT_GT(hi - lo, 0.1) << "the speed should actually vary";
}

TEST(Motion, ManoeuvresTiltZigzagBumpsAndYawOffset) {
  MotionConfig config;
  config.speed_jitter = 0;
  config.tilt_deg = 20;
  config.zigzag_deg = 15;
  config.zigzag_period_m = 20;
  config.bumps_deg = 10;
  config.yaw_offset_deg = 90;
  std::vector<TrajectoryPoint> t;
  ASSERT_TRUE(BuildTrajectory(kStraight, false, config, &t).ok());
  double max_roll = 0, max_bump = 0, max_weave = 0;
  for (const TrajectoryPoint& p : t) {
    max_roll = std::max(max_roll, std::fabs(p.pose.roll_deg));
    max_bump = std::max(max_bump, std::fabs(p.pose.pitch_deg - 20));
    const double expected_weave = 15 * std::sin(2 * M_PI * p.route_m / 20);
    EXPECT_NEAR(p.pose.yaw_deg, 90 + expected_weave, 1e-6);
    max_weave = std::max(max_weave, std::fabs(p.pose.yaw_deg - 90));
  }
  EXPECT_LE(max_roll, 10);
  EXPECT_LE(max_bump, 10);
  EXPECT_GT(max_roll, 3) << "bumps should use a good part of their range";
  EXPECT_GT(max_weave, 14);
}

TEST(Motion, ClosedLoopRunsOneLapFromAnyStart) {
  const std::vector<Point2> square = {{0, 0}, {10, 0}, {10, 10}, {0, 10}};
  MotionConfig config;
  config.speed_jitter = 0;
  config.start_m = 15;
  std::vector<TrajectoryPoint> t;
  ASSERT_TRUE(BuildTrajectory(square, true, config, &t).ok());
  EXPECT_EQ(t.size(), 41u);
  EXPECT_NEAR(t[0].pose.x_m, 10, 1e-9);
  EXPECT_NEAR(t[0].pose.y_m, 5, 1e-9);
  EXPECT_NEAR(t[0].pose.yaw_deg, 90, 1e-6);
  EXPECT_NEAR(t[0].route_m, 15, 1e-9);
  EXPECT_NEAR(t[30].route_m, 5, 1e-9);  // wrapped past the start
}

TEST(Motion, BadConfigurationIsRejected) {
  std::vector<TrajectoryPoint> t;
  MotionConfig config;
  config.frame_spacing_m = 0;
  EXPECT_EQ(BuildTrajectory(kStraight, false, config, &t).code(), StatusCode::kInvalidArgument);
  config = MotionConfig{};
  config.bumps_deg = 60;
  EXPECT_EQ(BuildTrajectory(kStraight, false, config, &t).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(BuildTrajectory(std::vector<Point2>{{0, 0}}, false, MotionConfig{}, &t).code(),
            StatusCode::kInvalidArgument);
}

std::string WriteTemp(const char* name, const char* contents) {
  const std::string path = (std::filesystem::temp_directory_path() / name).string();
  std::FILE* f = std::fopen(path.c_str(), "w");
  std::fputs(contents, f);
  std::fclose(f);
  return path;
}

TEST(Motion, RouteCsvInCentimetresAndMetres) {
  const std::string cm =
      WriteTemp("skyloc_sim_route_cm.csv", "x_cm,y_cm,heading_deg\n630,845,-124\n629.5,844,-124\n");
  std::vector<Point2> route;
  ASSERT_TRUE(LoadRouteCsv(cm.c_str(), &route).ok());
  ASSERT_EQ(route.size(), 2u);
  EXPECT_NEAR(route[0].x, 6.30, 1e-12);
  EXPECT_NEAR(route[0].y, 8.45, 1e-12);
  const std::string m = WriteTemp("skyloc_sim_route_m.csv", "x_m,y_m\n1,2\n3,4\n");
  ASSERT_TRUE(LoadRouteCsv(m.c_str(), &route).ok());
  EXPECT_EQ(route[1].x, 3);
  const std::string bad = WriteTemp("skyloc_sim_route_bad.csv", "x,y\n1,2\n");
  const Status s = LoadRouteCsv(bad.c_str(), &route);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(s.message()).find("x_cm,y_cm"), std::string::npos);
  std::filesystem::remove(cm);
  std::filesystem::remove(m);
  std::filesystem::remove(bad);
}

TEST(Motion, SevilleAntRouteLoads) {
  const std::string path =
      std::string(SKYLOC_SHARED_DIR) + "/data/seville2009/routes/ant1_route1.csv";
  if (!std::filesystem::exists(path))
    GTEST_SKIP() << path << " not found (the shared data folder is not next to the repo)";
  std::vector<Point2> route;
  ASSERT_TRUE(LoadRouteCsv(path.c_str(), &route).ok());
  // Homeward: from the feeder near (6.30, 8.45) m to the nest near (5.10, 1.00) m.
  EXPECT_NEAR(route.front().x, 6.30, 0.2);
  EXPECT_NEAR(route.front().y, 8.45, 0.2);
  EXPECT_NEAR(route.back().x, 5.10, 0.5);
  EXPECT_NEAR(route.back().y, 1.00, 0.5);
}

}  // namespace
}  // namespace skyloc::sim
