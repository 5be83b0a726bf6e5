#include "skyloc/sim/motion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <span>
#include <string>
#include <utility>
#include <vector>

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

// Values the distance sampling gave before time sampling existed (the code at 0e1072a),
// printed with %a: distance sampling must stay as it was for every existing caller. Exact
// on one build; the 1e-12 tolerance only admits libm's last-bit differences between
// architectures (atan2, sin, hypot), far below what one changed random draw would move.
TEST(Motion, DistanceSamplingIsUnchanged) {
  struct Expected {
    std::size_t i;
    double x, y, roll, pitch, yaw, time, route;
  };
  const std::vector<Point2> route = {{0, 0}, {30, 0}, {30, 20}, {5, 25}};
  MotionConfig config;
  config.bumps_deg = 10;
  config.zigzag_deg = 15;
  config.tilt_deg = 5;
  config.seed = 42;
  config.start_m = 3;
  const Expected open[] = {
      {0, 0x1.8p+1, 0x0p+0, -0x1.baded97ce64e2p+0, 0x1.a8fb17986b64ap+2, 0x1.8454021de755ep+3,
       0x0p+0, 0x1.8p+1},
      {1, 0x1.032dbf970da14p+2, 0x0p+0, -0x1.e56f58bfc8a2ap+0, 0x1.aa4791db8170cp+2,
       0x1.cac4116c5114ap+3, 0x1.999999999999ap-4, 0x1.032dbf970da14p+2},
      {17, 0x1.53597607f302bp+4, 0x0p+0, -0x1.ded12b6f03c5cp-1, 0x1.158e8b7089077p+3,
       0x1.640475421ddbcp+2, 0x1.b333333333334p+0, 0x1.53597607f302bp+4},
      {77, 0x1.483402d2c2f1cp+2, 0x1.8f96ffdbdca72p+4, 0x1.24256a5021584p-1, 0x1.6df7332702d31p+3,
       0x1.339394b44e587p+7, 0x1.ecccccccccccdp+2, 0x1.2d75214409d54p+6},
  };
  const Expected closed[] = {
      {17, 0x1.53597607f302cp+4, 0x0p+0, -0x1.ded12b6f03c5cp-1, 0x1.158e8b7089077p+3,
       0x1.640475421ddbcp+2, 0x1.b333333333334p+0, 0x1.53597607f302bp+4},
      {107, 0x1.1ae1a7ce2832p+1, 0x0p+0, -0x1.4bec354d2a67ap+0, 0x1.d937917d1e45ap+3,
       0x1.954b49e72b697p+3, 0x1.5666666666667p+3, 0x1.1ae1a7ce2832p+1},
  };
  for (const bool is_closed : {false, true}) {
    std::vector<TrajectoryPoint> t;
    ASSERT_TRUE(BuildTrajectory(route, is_closed, config, &t).ok());
    ASSERT_EQ(t.size(), is_closed ? 108u : 78u);
    for (const Expected& e : is_closed ? std::span<const Expected>(closed) : open) {
      SCOPED_TRACE(testing::Message() << (is_closed ? "closed" : "open") << " frame " << e.i);
      const TrajectoryPoint& p = t[e.i];
      EXPECT_NEAR(p.pose.x_m, e.x, 1e-12);
      EXPECT_NEAR(p.pose.y_m, e.y, 1e-12);
      EXPECT_NEAR(p.pose.roll_deg, e.roll, 1e-12);
      EXPECT_NEAR(p.pose.pitch_deg, e.pitch, 1e-12);
      EXPECT_NEAR(p.pose.yaw_deg, e.yaw, 1e-12);
      EXPECT_NEAR(p.time_s, e.time, 1e-12);
      EXPECT_NEAR(p.route_m, e.route, 1e-12);
    }
  }
}

MotionConfig TimeSampled() {
  MotionConfig config;
  config.sampling = Sampling::kTime;
  config.fps = 10;
  return config;
}

// Runs of consecutive frames whose whole pose is identical: (first index, length).
std::vector<std::pair<std::size_t, std::size_t>> StandingRuns(
    const std::vector<TrajectoryPoint>& t) {
  std::vector<std::pair<std::size_t, std::size_t>> runs;
  for (std::size_t i = 1; i < t.size(); ++i) {
    const drivers::Pose& a = t[i].pose;
    const drivers::Pose& b = t[i - 1].pose;
    if (a.x_m != b.x_m || a.y_m != b.y_m || a.z_m != b.z_m || a.roll_deg != b.roll_deg ||
        a.pitch_deg != b.pitch_deg || a.yaw_deg != b.yaw_deg)
      continue;
    if (!runs.empty() && runs.back().first + runs.back().second == i)
      ++runs.back().second;
    else
      runs.push_back({i - 1, 2});
  }
  return runs;
}

TEST(Motion, TimeSampledFramesStepByThePeriod) {
  MotionConfig config = TimeSampled();
  config.fps = 25;
  std::vector<TrajectoryPoint> t;
  ASSERT_TRUE(BuildTrajectory(kStraight, false, config, &t).ok());
  ASSERT_GT(t.size(), 100u);
  for (std::size_t i = 0; i < t.size(); ++i)
    ASSERT_NEAR(t[i].time_s, static_cast<double>(i) / 25.0, 1e-9) << "frame " << i;
  EXPECT_NEAR(t.front().route_m, 0, 1e-12);
  EXPECT_NEAR(t.back().route_m, 100, 1e-6) << "the run ends at the end of the route";
}

// The trapezoid rule is exact for a speed that is piecewise linear in time, except in the
// frame intervals where the acceleration changes (a start, a stop, a new cruise target):
// each such kink costs at most a_max h^2 / 4 = 1.25 mm (a = 0.5, h = 0.1 s). A 100 m run
// with two stops and cruise changes every ~30 m has under 20 kinks: 25 mm bounds it.
TEST(Motion, ArcLengthIsTheIntegralOfTheSpeed) {
  MotionConfig config = TimeSampled();
  config.bumps_deg = 5;
  std::vector<TrajectoryPoint> t;
  ASSERT_TRUE(BuildTrajectory(kStraight, false, config, &t).ok());
  double integral = 0;
  for (std::size_t i = 1; i < t.size(); ++i)
    integral += 0.5 * (t[i].speed_mps + t[i - 1].speed_mps) * (t[i].time_s - t[i - 1].time_s);
  EXPECT_NEAR(integral, t.back().route_m - t.front().route_m, 0.025);
  EXPECT_NEAR(t.back().route_m, 100, 1e-6);
}

TEST(Motion, StopsRepeatThePoseForTheirDuration) {
  MotionConfig config = TimeSampled();
  config.bumps_deg = 5;  // a standing robot does not bump: the whole pose repeats
  config.speed.start_stop_s = 2;
  config.speed.stops = 1;
  config.speed.stop_min_s = 3.5;
  config.speed.stop_max_s = 3.5;
  std::vector<TrajectoryPoint> t;
  ASSERT_TRUE(BuildTrajectory(kStraight, false, config, &t).ok());
  const auto runs = StandingRuns(t);
  ASSERT_EQ(runs.size(), 2u) << "the start and one stop; elsewhere every frame moves";
  EXPECT_EQ(runs[0].first, 0u);
  EXPECT_NEAR(static_cast<double>(runs[0].second), 2 * 10, 1);
  EXPECT_NEAR(static_cast<double>(runs[1].second), 3.5 * 10, 1);
  for (std::size_t i = runs[1].first; i < runs[1].first + runs[1].second; ++i)
    EXPECT_EQ(t[i].speed_mps, 0) << "frame " << i;
  const double stop_m = t[runs[1].first].route_m;
  EXPECT_GT(stop_m, 5);
  EXPECT_LT(stop_m, 95);
  // Another run seed stops elsewhere (a repeat run does not stop where the taught one did).
  config.seed = 2;
  ASSERT_TRUE(BuildTrajectory(kStraight, false, config, &t).ok());
  const auto other = StandingRuns(t);
  ASSERT_EQ(other.size(), 2u);
  EXPECT_GT(std::fabs(t[other[1].first].route_m - stop_m), 1.0);
}

TEST(Motion, AccelerationNeverExceedsTheLimit) {
  MotionConfig config = TimeSampled();
  config.speed.cruise_mps = 2;
  config.speed.accel_mps2 = 0.8;
  config.speed.stops = 4;
  config.speed.change_every_m = 10;
  std::vector<TrajectoryPoint> t;
  ASSERT_TRUE(BuildTrajectory(kStraight, false, config, &t).ok());
  const double h = 0.1;
  double largest = 0;
  for (std::size_t i = 1; i + 1 < t.size(); ++i) {
    // The second difference of the positions: the mean acceleration over two frames.
    const double a = (t[i + 1].route_m - 2 * t[i].route_m + t[i - 1].route_m) / (h * h);
    largest = std::max(largest, std::fabs(a));
    ASSERT_LE(std::fabs(a), 0.8 * (1 + 1e-6)) << "frame " << i;
    ASSERT_LE(std::fabs(t[i].speed_mps - t[i - 1].speed_mps), 0.8 * h * (1 + 1e-6));
  }
  EXPECT_GT(largest, 0.7) << "the profile should actually use its acceleration";
}

// Without stops or cruise changes the run time is analytic: accelerate to v at a, cruise,
// brake at a: T = L / v + v / a. 100 m at 1 m/s: 102 s (1021 frames at 10 fps); twice as
// fast: 54 s (541 frames), not quite half because the speed-up and slow-down take longer.
// The profile is planned on 1 cm nodes, so the time may differ from T by a frame or two.
TEST(Motion, SpeedRatioScalesTheRunTime) {
  MotionConfig config = TimeSampled();
  config.speed.band = 0;
  config.speed.stops = 0;
  config.speed.start_stop_s = 0;
  std::vector<TrajectoryPoint> slow, fast;
  ASSERT_TRUE(BuildTrajectory(kStraight, false, config, &slow).ok());
  config.speed_ratio = 2;
  ASSERT_TRUE(BuildTrajectory(kStraight, false, config, &fast).ok());
  EXPECT_NEAR(static_cast<double>(slow.size()), 1021, 2);
  EXPECT_NEAR(static_cast<double>(fast.size()), 541, 2);
  EXPECT_NEAR(fast[fast.size() / 2].speed_mps, 2, 1e-9);
  config.speed_ratio = 0.3;
  ASSERT_TRUE(BuildTrajectory(kStraight, false, config, &slow).ok());
  EXPECT_NEAR(static_cast<double>(slow.size()), (100 / 0.3 + 0.3 / 0.5) * 10 + 1, 2);
}

TEST(Motion, TimeSampledClosedLoopRunsOneLap) {
  const std::vector<Point2> square = {{0, 0}, {10, 0}, {10, 10}, {0, 10}};
  MotionConfig config = TimeSampled();
  config.start_m = 15;
  std::vector<TrajectoryPoint> t;
  ASSERT_TRUE(BuildTrajectory(square, true, config, &t).ok());
  EXPECT_NEAR(t.front().route_m, 15, 1e-9);
  EXPECT_NEAR(t.front().pose.x_m, 10, 1e-9);
  EXPECT_NEAR(t.back().route_m, 15, 1e-6) << "one lap back to the start";
}

TEST(Motion, BadSpeedProfileIsRejected) {
  std::vector<TrajectoryPoint> t;
  auto code = [&](void (*edit)(MotionConfig*)) {
    MotionConfig config = TimeSampled();
    edit(&config);
    return BuildTrajectory(kStraight, false, config, &t).code();
  };
  EXPECT_EQ(code([](MotionConfig*) {}), StatusCode::kOk);
  EXPECT_EQ(code([](MotionConfig* c) { c->fps = 0; }), StatusCode::kInvalidArgument);
  EXPECT_EQ(code([](MotionConfig* c) { c->speed.cruise_mps = 0; }), StatusCode::kInvalidArgument);
  EXPECT_EQ(code([](MotionConfig* c) { c->speed.accel_mps2 = -1; }), StatusCode::kInvalidArgument);
  EXPECT_EQ(code([](MotionConfig* c) { c->speed.band = 1; }), StatusCode::kInvalidArgument);
  EXPECT_EQ(code([](MotionConfig* c) { c->speed.stops = -1; }), StatusCode::kInvalidArgument);
  EXPECT_EQ(code([](MotionConfig* c) { c->speed.stop_min_s = 7; }),
            StatusCode::kInvalidArgument);  // above the maximum, 6 s
  EXPECT_EQ(code([](MotionConfig* c) { c->speed_ratio = 0; }), StatusCode::kInvalidArgument);
  EXPECT_EQ(code([](MotionConfig* c) { c->start_m = 200; }), StatusCode::kInvalidArgument);
}

std::string WriteTemp(const char* name, const char* contents) {
  const std::string path = (std::filesystem::temp_directory_path() / name).string();
  std::FILE* f = std::fopen(path.c_str(), "w");
  std::fputs(contents, f);
  std::fclose(f);
  return path;
}

// The sideways wander, on a straight route along x, where the offset is y itself: bounded
// by A, used (a 200 m route covers at least 2.5 periods of its slower sine), smooth (the
// bound of its slope: A 2 pi (0.6 / 40 + 0.4 / 12) per metre), and nothing else moves:
// time, route distance, speed and attitude are those of the run on the line, with both
// samplings and stops (a standing robot stands at its offset).
TEST(Motion, LateralWanderMovesOnlyThePositionSidewaysWithinItsBound) {
  const std::vector<Point2> straight = {{0, 0}, {200, 0}};
  for (const Sampling sampling : {Sampling::kDistance, Sampling::kTime}) {
    MotionConfig config = sampling == Sampling::kTime ? TimeSampled() : MotionConfig{};
    config.bumps_deg = 10;
    config.zigzag_deg = 15;
    config.seed = 7;
    std::vector<TrajectoryPoint> on_line, wandering;
    ASSERT_TRUE(BuildTrajectory(straight, false, config, &on_line).ok());
    config.lateral_m = 1.5;
    ASSERT_TRUE(BuildTrajectory(straight, false, config, &wandering).ok());
    ASSERT_EQ(wandering.size(), on_line.size());
    const double slope_bound = 1.5 * 2 * M_PI * (0.6 / 40 + 0.4 / 12);
    double largest = 0;
    for (std::size_t i = 0; i < wandering.size(); ++i) {
      const TrajectoryPoint& a = wandering[i];
      const TrajectoryPoint& b = on_line[i];
      EXPECT_EQ(a.time_s, b.time_s);
      EXPECT_EQ(a.route_m, b.route_m);
      EXPECT_EQ(a.speed_mps, b.speed_mps);
      EXPECT_EQ(a.pose.x_m, b.pose.x_m);
      EXPECT_EQ(a.pose.z_m, b.pose.z_m);
      EXPECT_EQ(a.pose.roll_deg, b.pose.roll_deg);
      EXPECT_EQ(a.pose.pitch_deg, b.pose.pitch_deg);
      EXPECT_EQ(a.pose.yaw_deg, b.pose.yaw_deg);
      EXPECT_EQ(b.pose.y_m, 0);
      EXPECT_LE(std::fabs(a.pose.y_m), 1.5 + 1e-12);
      largest = std::max(largest, std::fabs(a.pose.y_m));
      if (i > 0) {
        const double ds = a.route_m - wandering[i - 1].route_m;
        EXPECT_LE(std::fabs(a.pose.y_m - wandering[i - 1].pose.y_m), slope_bound * ds + 1e-12)
            << "frame " << i;
      }
    }
    EXPECT_GT(largest, 0.75) << "the wander should use a good part of its range";
  }
  std::vector<TrajectoryPoint> t;
  MotionConfig config;
  config.lateral_m = 5.5;
  EXPECT_EQ(BuildTrajectory(straight, false, config, &t).code(), StatusCode::kInvalidArgument);
  config.lateral_m = -1;
  EXPECT_EQ(BuildTrajectory(straight, false, config, &t).code(), StatusCode::kInvalidArgument);
}

// On a closed loop the route distance wraps to 0 at the seam; the wander must not jump
// there. A 200-gon of radius 50 m (a circle to 6 mm), one lap from 200 m, so the seam
// (314 m) falls mid-run: the offset (distance from the centre - 50) changes between frames
// by at most the wander's slope bound times the step, everywhere.
TEST(Motion, LateralWanderIsContinuousAcrossAClosedLoopsSeam) {
  std::vector<Point2> circle;
  for (int i = 0; i < 200; ++i) {
    const double a = 2 * M_PI * i / 200;
    circle.push_back({50 * std::cos(a), 50 * std::sin(a)});
  }
  MotionConfig config;
  config.speed_jitter = 0;
  config.start_m = 200;
  config.lateral_m = 2;
  std::vector<TrajectoryPoint> t;
  ASSERT_TRUE(BuildTrajectory(circle, true, config, &t).ok());
  const double slope_bound = 2 * 2 * M_PI * (0.6 / 40 + 0.4 / 12);
  bool crossed_seam = false;
  for (std::size_t i = 1; i < t.size(); ++i) {
    crossed_seam |= t[i].route_m < t[i - 1].route_m;
    const double offset = std::hypot(t[i].pose.x_m, t[i].pose.y_m) - 50;
    const double previous = std::hypot(t[i - 1].pose.x_m, t[i - 1].pose.y_m) - 50;
    EXPECT_LE(std::fabs(offset - previous), slope_bound * 1.0 + 0.02) << "frame " << i;
  }
  EXPECT_TRUE(crossed_seam);
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
