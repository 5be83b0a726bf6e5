// A simulated run: the configuration's sim_* keys, the command line's SIM flags and
// `skyloc simulate` fill one SimRunConfig, and one conversion makes the simulator's motion.
#include "firmware/sim_run.h"

#include <gtest/gtest.h>

#include "firmware/config.h"

namespace skyloc::firmware {
namespace {

SimRunConfig EveryFieldSet() {
  SimRunConfig r;
  r.world = "forest";
  r.seed = 7;
  r.run_seed = 9;
  r.sampling = SimSampling::kTime;
  r.spacing_m = 0.5;
  r.speed_jitter = 0.1;
  r.speed.cruise_mps = 2.5;
  r.speed.band = 0.2;
  r.speed.accel_mps2 = 0.75;
  r.speed.start_stop_s = 3;
  r.speed.stops = 4;
  r.speed.stop_min_s = 1;
  r.speed.stop_max_s = 5;
  r.speed_ratio = 1.5;
  r.camera_height_m = 2;
  r.tilt_deg = 10;
  r.zigzag_deg = 20;
  r.bumps_deg = 3;
  r.yaw_deg = 45;
  r.lighting = "dawn";
  return r;
}

TEST(SimRun, MotionCarriesEveryField) {
  const sim::MotionConfig m = SimMotionConfig(EveryFieldSet(), 12.5);
  EXPECT_EQ(m.sampling, sim::Sampling::kTime);
  EXPECT_EQ(m.frame_spacing_m, 0.5);
  EXPECT_EQ(m.speed_jitter, 0.1);
  EXPECT_EQ(m.speed.cruise_mps, 2.5);
  EXPECT_EQ(m.speed.band, 0.2);
  EXPECT_EQ(m.speed.accel_mps2, 0.75);
  EXPECT_EQ(m.speed.start_stop_s, 3.0);
  EXPECT_EQ(m.speed.stops, 4);
  EXPECT_EQ(m.speed.stop_min_s, 1.0);
  EXPECT_EQ(m.speed.stop_max_s, 5.0);
  EXPECT_EQ(m.speed_ratio, 1.5);
  EXPECT_EQ(m.fps, 12.5);
  EXPECT_EQ(m.height_m, 2.0);
  EXPECT_EQ(m.tilt_deg, 10.0);
  EXPECT_EQ(m.zigzag_deg, 20.0);
  EXPECT_EQ(m.bumps_deg, 3.0);
  EXPECT_EQ(m.yaw_offset_deg, 45.0);
  EXPECT_EQ(m.seed, 9u);
  // Not part of a run's description: the simulator's own defaults.
  const sim::MotionConfig defaults;
  EXPECT_EQ(m.zigzag_period_m, defaults.zigzag_period_m);
  EXPECT_EQ(m.speed.change_every_m, defaults.speed.change_every_m);
  EXPECT_EQ(m.lateral_m, 0.0);
  EXPECT_EQ(m.start_m, 0.0);
  EXPECT_EQ(m.max_frames, 0);
}

// The defaults of a run are the simulator's: a default SimRunConfig moves as a default
// MotionConfig does.
TEST(SimRun, DefaultsAreTheSimulatorsDefaults) {
  const sim::MotionConfig m = SimMotionConfig(SimRunConfig{}, 10);
  const sim::MotionConfig d;
  EXPECT_EQ(m.sampling, sim::Sampling::kDistance);
  EXPECT_EQ(m.frame_spacing_m, d.frame_spacing_m);
  EXPECT_EQ(m.speed_jitter, d.speed_jitter);
  EXPECT_EQ(m.speed.cruise_mps, d.speed.cruise_mps);
  EXPECT_EQ(m.speed.band, d.speed.band);
  EXPECT_EQ(m.speed.accel_mps2, d.speed.accel_mps2);
  EXPECT_EQ(m.speed.start_stop_s, d.speed.start_stop_s);
  EXPECT_EQ(m.speed.stops, d.speed.stops);
  EXPECT_EQ(m.speed.stop_min_s, d.speed.stop_min_s);
  EXPECT_EQ(m.speed.stop_max_s, d.speed.stop_max_s);
  EXPECT_EQ(m.speed_ratio, d.speed_ratio);
  EXPECT_EQ(m.height_m, d.height_m);
  EXPECT_EQ(m.seed, d.seed);
}

TEST(SimRun, SimulateStartsInTimeAndSevilleIsAnAnt) {
  EXPECT_EQ(SimulateDefaults(false).sampling, SimSampling::kTime);
  EXPECT_EQ(SimulateDefaults(false).speed.cruise_mps, 1.0);
  EXPECT_EQ(SimulateDefaults(false).camera_height_m, 1.0);
  EXPECT_EQ(SimulateDefaults(true).speed.cruise_mps, 0.5);
  EXPECT_EQ(SimulateDefaults(true).camera_height_m, 0.01);
}

// The world and its sampling are the configuration's; the run is the command line's.
TEST(SimRun, ConfiguredRunTakesTheWorldFromTheConfigAndTheRunFromTheFlags) {
  SimRunConfig configured = EveryFieldSet();
  SimRunConfig flags;
  flags.world = "repetitive";  // not a flag: ignored
  flags.sampling = SimSampling::kDistance;
  flags.run_seed = 3;
  flags.tilt_deg = -5;
  flags.lighting = "overcast";
  flags.speed_ratio = 2;
  const SimRunConfig run = ConfiguredSimRun(configured, flags);
  EXPECT_EQ(run.world, "forest");
  EXPECT_EQ(run.seed, 7u);
  EXPECT_EQ(run.sampling, SimSampling::kTime);
  EXPECT_EQ(run.speed.cruise_mps, 2.5);
  EXPECT_EQ(run.speed.stops, 4);
  EXPECT_EQ(run.run_seed, 3u);
  EXPECT_EQ(run.tilt_deg, -5.0);
  EXPECT_EQ(run.zigzag_deg, 0.0);
  EXPECT_EQ(run.lighting, "overcast");
  EXPECT_EQ(run.speed_ratio, 2.0);
}

TEST(SimRun, LightingIsAPresetOrRefused) {
  SimRunConfig run;
  run.lighting = "dawn";
  EXPECT_TRUE(SimLighting(run).ok());
  run.lighting = "dusk";
  const Result<sim::Lighting> bad = SimLighting(run);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(bad.status().message()).find("\"dusk\""), std::string::npos);
}

// The [camera] sim_* keys land in the one struct.
TEST(SimRun, ConfigKeysFillTheRun) {
  const Result<Config> c = ParseConfig(
      "[camera]\nsim_world = \"forest\"\nsim_seed = 5\nsim_sampling = \"time\"\n"
      "sim_speed_mps = 2.0\nsim_speed_band = 0.1\nsim_accel_mps2 = 1.5\n"
      "sim_start_stop_s = 0\nsim_stops = 3\nsim_stop_min_s = 1\nsim_stop_max_s = 2\n",
      "robot.toml");
  ASSERT_TRUE(c.ok()) << c.status().message();
  const SimRunConfig& s = c->camera.sim;
  EXPECT_EQ(s.world, "forest");
  EXPECT_EQ(s.seed, 5u);
  EXPECT_EQ(s.sampling, SimSampling::kTime);
  EXPECT_EQ(s.speed.cruise_mps, 2.0);
  EXPECT_EQ(s.speed.band, 0.1);
  EXPECT_EQ(s.speed.accel_mps2, 1.5);
  EXPECT_EQ(s.speed.start_stop_s, 0.0);
  EXPECT_EQ(s.speed.stops, 3);
  EXPECT_EQ(s.speed.stop_min_s, 1.0);
  EXPECT_EQ(s.speed.stop_max_s, 2.0);
  EXPECT_EQ(DefaultConfig().camera.sim, SimRunConfig{});
}

}  // namespace
}  // namespace skyloc::firmware
