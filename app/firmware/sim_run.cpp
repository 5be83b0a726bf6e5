#include "firmware/sim_run.h"

namespace skyloc::firmware {

SimRunConfig SimulateDefaults(bool seville) {
  SimRunConfig run;
  run.world.frames.sampling = sim::Sampling::kTime;
  if (seville) {
    run.world.frames.speed.cruise_mps = 0.5;  // an ant-sized run: 5 cm frames at 10 fps
    run.ride.height_m = 0.01;
  }
  return run;
}

SimRunConfig ConfiguredSimRun(const SimWorldConfig& configured, const SimRunConfig& command_line) {
  SimRunConfig run = command_line;
  run.world = configured;
  return run;
}

sim::MotionConfig SimMotionConfig(const SimRunConfig& run, double fps,
                                  const sim::MotionConfig& base) {
  sim::MotionConfig motion = base;
  motion.Resample(run.world.frames);
  motion.SetRide(run.ride);
  motion.fps = fps;
  return motion;
}

Result<sim::Lighting> SimLighting(const SimRunConfig& run) {
  sim::Lighting lighting;
  if (!sim::LightingPreset(run.lighting.c_str(), run.ride.seed, &lighting))
    return Status::Error(StatusCode::kInvalidArgument,
                         "lighting \"%s\" is not dawn, noon or overcast", run.lighting.c_str());
  return lighting;
}

}  // namespace skyloc::firmware
