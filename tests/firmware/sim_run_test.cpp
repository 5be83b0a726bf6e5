// A simulated run: the configuration's sim_* keys (its world), the command line's SIM flags
// and `skyloc simulate` fill one SimRunConfig, and one conversion makes the simulator's
// motion.
#include "firmware/sim_run.h"

#include <gtest/gtest.h>

#include "firmware/config.h"

namespace skyloc::firmware {
namespace {

SimRunConfig EveryFieldSet() {
  SimRunConfig r;
  r.world.name = "forest";
  r.world.seed = 7;
  r.world.frames.sampling = sim::Sampling::kTime;
  r.world.frames.frame_spacing_m = 0.5;
  r.world.frames.speed_jitter = 0.1;
  r.world.frames.speed.cruise_mps = 2.5;
  r.world.frames.speed.band = 0.2;
  r.world.frames.speed.accel_mps2 = 0.75;
  r.world.frames.speed.start_stop_s = 3;
  r.world.frames.speed.stops = 4;
  r.world.frames.speed.stop_min_s = 1;
  r.world.frames.speed.stop_max_s = 5;
  r.ride = {.speed_ratio = 1.5,
            .height_m = 2,
            .tilt_deg = 10,
            .zigzag_deg = 20,
            .bumps_deg = 3,
            .yaw_offset_deg = 45,
            .seed = 9};
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

// `skyloc simulate`'s own options ride in the base; the run overrides only what it
// describes.
TEST(SimRun, MotionKeepsTheBasesOwnFields) {
  sim::MotionConfig base;
  base.zigzag_period_m = 7;
  base.lateral_m = 1.5;
  base.start_m = 30;
  base.max_frames = 99;
  base.tilt_deg = 80;  // the run's: replaced
  const sim::MotionConfig m = SimMotionConfig(EveryFieldSet(), 12.5, base);
  EXPECT_EQ(m.zigzag_period_m, 7.0);
  EXPECT_EQ(m.lateral_m, 1.5);
  EXPECT_EQ(m.start_m, 30.0);
  EXPECT_EQ(m.max_frames, 99);
  EXPECT_EQ(m.tilt_deg, 10.0);
  EXPECT_EQ(m.fps, 12.5);
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
  EXPECT_EQ(SimulateDefaults(false).world.frames.sampling, sim::Sampling::kTime);
  EXPECT_EQ(SimulateDefaults(false).world.frames.speed.cruise_mps, 1.0);
  EXPECT_EQ(SimulateDefaults(false).ride.height_m, 1.0);
  EXPECT_EQ(SimulateDefaults(true).world.frames.speed.cruise_mps, 0.5);
  EXPECT_EQ(SimulateDefaults(true).ride.height_m, 0.01);
}

// The world and its sampling are the configuration's; the run is the command line's.
TEST(SimRun, ConfiguredRunTakesTheWorldFromTheConfigAndTheRunFromTheFlags) {
  const SimWorldConfig configured = EveryFieldSet().world;
  SimRunConfig flags;
  flags.world.name = "repetitive";  // not a flag: ignored
  flags.world.frames.sampling = sim::Sampling::kDistance;
  flags.ride.seed = 3;
  flags.ride.tilt_deg = -5;
  flags.lighting = "overcast";
  flags.ride.speed_ratio = 2;
  const SimRunConfig run = ConfiguredSimRun(configured, flags);
  EXPECT_EQ(run.world, configured);
  EXPECT_EQ(run.world.name, "forest");
  EXPECT_EQ(run.world.frames.sampling, sim::Sampling::kTime);
  EXPECT_EQ(run.ride.seed, 3u);
  EXPECT_EQ(run.ride.tilt_deg, -5.0);
  EXPECT_EQ(run.ride.zigzag_deg, 0.0);
  EXPECT_EQ(run.lighting, "overcast");
  EXPECT_EQ(run.ride.speed_ratio, 2.0);
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

// The [camera] sim_* keys fill the run's world.
TEST(SimRun, ConfigKeysFillTheRun) {
  const Result<Config> c = ParseConfig(
      "[camera]\nsim_world = \"forest\"\nsim_seed = 5\nsim_sampling = \"time\"\n"
      "sim_speed_mps = 2.0\nsim_speed_band = 0.1\nsim_accel_mps2 = 1.5\n"
      "sim_start_stop_s = 0\nsim_stops = 3\nsim_stop_min_s = 1\nsim_stop_max_s = 2\n",
      "robot.toml");
  ASSERT_TRUE(c.ok()) << c.status().message();
  const SimWorldConfig& s = c->camera.sim;
  EXPECT_EQ(s.name, "forest");
  EXPECT_EQ(s.seed, 5u);
  EXPECT_EQ(s.frames.sampling, sim::Sampling::kTime);
  EXPECT_EQ(s.frames.speed.cruise_mps, 2.0);
  EXPECT_EQ(s.frames.speed.band, 0.1);
  EXPECT_EQ(s.frames.speed.accel_mps2, 1.5);
  EXPECT_EQ(s.frames.speed.start_stop_s, 0.0);
  EXPECT_EQ(s.frames.speed.stops, 3);
  EXPECT_EQ(s.frames.speed.stop_min_s, 1.0);
  EXPECT_EQ(s.frames.speed.stop_max_s, 2.0);
  EXPECT_EQ(DefaultConfig().camera.sim, SimRunConfig{}.world);
}

}  // namespace
}  // namespace skyloc::firmware
